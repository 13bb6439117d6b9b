"""The probe's cases and their runner, with no middleware: ``dynevent probe`` over any :class:`Link`.

The probe is a client that may break the protocol on purpose: it sends raw
goals (a stale seq, event type 0, a CANCEL naming another event...) and watches
the robot's status and begin topics.  Each case of
:data:`dynevent.conformance.probe.cases.CASES` ends in a
:class:`~dynevent.conformance.probe.cases.CaseFinding`; every wait is bounded by
``--timeout`` and the whole run by ``--deadline``.  A refusal carries no reason
on the wire (D6), so a case judges what a client can see: accepted or
rejected, the feedback, the answer, the status that follows.

The cases reach the server through a :class:`Link`: raw access to one robot
(send a goal, cancel one, the statuses and begins heard, the clock, and a wait
for what it hears).  dynevent.ros carries the link over DDS;
:mod:`dynevent.conformance.probe.in_process` runs the machine itself, as ``dynevent
serve`` configures it, on simulated time, so that every case runs in the core
test suite without ROS (``dynevent probe --loopback``).
"""

from __future__ import annotations

import itertools
import json
import math
import os
import shlex
import subprocess
import threading
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import Any

import attrs

from dynevent.conformance.judge.trace import TraceWriter
from dynevent.conformance.probe import cases as probe_cases
from dynevent.conformance.probe.cases import Case, CaseFinding, Verdict
from dynevent.conformance.vectors.report import took_line
from dynevent.server import machine
from dynevent.wire._fields import U32_MAX, U64_MAX, id_not_after, seq_after
from dynevent.wire._text import goal_text, status_text
from dynevent.wire.messages import (
    DynamicEventDescription,
    DynamicEventStatus,
    Feedback,
    Goal,
    LogEntry,
    Result,
)
from dynevent.wire.vocab import DynamicState, EventType, Failure, GoalStatus, Status, Tier

__all__ = [
    "STOPPED_ANSWERING",
    "Exchange",
    "Link",
    "Options",
    "Probe",
    "ReportWriter",
    "conclude",
    "implemented",
    "run_cases",
    "took",
]

_STANDBY, _UNDERWAY = Status.STANDBY.value, Status.UNDERWAY.value
_COMPLETED, _CANCELED = Status.COMPLETED.value, Status.CANCELED.value
_U32 = U32_MAX + 1
#: The configuration whose server numbers every child itself (id policy adapter): what a NEXT of id
#: 0 asks of any server (R6.2).
_SERVER_NUMBERS = machine.ServerConfig(id_policy="adapter")


def _within_ids(goal_id: int) -> int:
    """An id a case names beyond the next one; a case that needs one above 2**64 - 1 is not run."""
    if goal_id > U64_MAX:
        raise _Unreachable(f"the case needs id {goal_id}, above 2**64 - 1, the highest")
    return goal_id


def _fresh(last_id: int) -> int:
    """The id above ``last_id`` a NEXT names (R4.12, the machine's :func:`~dynevent.server.machine.fresh_id`);
    a case that needs one where none is left is not run."""
    fresh = machine.fresh_id(last_id)
    if fresh is None:
        raise _Unreachable(f"no id is left above {last_id} in this run (2**64 - 1 is the highest)")
    return fresh


class Exchange:
    """One raw goal: whether it was accepted, its feedback, and its answer, each as it arrives."""

    def __init__(self, goal: Goal, link: Link) -> None:
        self.goal = goal
        self.uuid = os.urandom(16).hex()
        self.accepted: bool | None = None
        self.feedback: list[Feedback] = []
        self.answers: list[tuple[GoalStatus, Result]] = []
        self.handle: Any = None  # the transport's handle on the goal, once accepted
        #: where among everything the link heard its response came, and its first answer (1 the first
        #: message heard), and how many statuses had come before its response: the order the probe
        #: heard things in, which a lossy link may make another than the server's
        self.response_heard: int | None = None
        self.answer_heard: int | None = None
        #: when its response came, by the link's clock
        self.response_at: float | None = None
        self.statuses_before_response = 0
        #: how many messages the link had heard when it was sent
        self.sent_heard = link.heard
        #: when the server accepted it, by the server's own clock (ns since the epoch), where the
        #: transport says
        self.accepted_at: int | None = None
        #: an action-level cancel of it was refused because the goal had terminated when the server
        #: took the request (where the transport says: ROS 2's ``ERROR_GOAL_TERMINATED``)
        self.cancel_found_ended = False
        #: how many action-level cancels of it were sent, and how many responses to them came
        self.cancels_asked = 0
        self.cancels_heard = 0
        self._link = link
        link.made.append(self)

    def wait(self, condition: Callable[[], bool], timeout: float) -> bool:
        """Wait, at most ``timeout`` seconds of the link's clock, until ``condition()`` holds."""
        return self._link.wait(condition, timeout)

    def responded(self, timeout: float) -> bool:
        return self.wait(lambda: self.accepted is not None, timeout)

    def answered(self, timeout: float) -> bool:
        return self.wait(lambda: bool(self.answers) or self.accepted is False, timeout)

    @property
    def cancel_heard(self) -> bool:
        """A response to an action-level cancel of it came."""
        return self.cancels_heard > 0

    @property
    def answer(self) -> tuple[GoalStatus, Result] | None:
        return self.answers[0] if self.answers else None


# the records of what the probe itself sends
_SENT = frozenset({"goal", "cancel_request"})


class Link:
    """Raw access to one robot, without a client machine, so that the probe can send what a
    well-behaved client never would: the transport's part is left to a subclass.

    A subclass sends (:meth:`send`, :meth:`cancel`, :meth:`describe`), tells what it hears
    (:meth:`hear_status`, :meth:`hear_begin`, :meth:`hear_response`, :meth:`hear_feedback`,
    :meth:`hear_answer`), and keeps the time (:meth:`clock`, :meth:`wait`).  Every record of the
    exchange, sent and heard, goes to the trace, which the judge reads."""

    def __init__(self, fleet: str, robot: str, trace: TraceWriter | None = None) -> None:
        self.fleet, self.robot = fleet, robot
        self._trace = trace
        #: the trace is a client's tap, which the judge reads as seen apart from the server: a feedback
        #: lost on the way is not told there from a server's gap (else the link loses nothing it hears)
        self.apart = trace is not None and trace.tap == "client"
        self.statuses: list[DynamicEventStatus] = []
        self.begins: list[DynamicEventDescription] = []
        self.made: list[Exchange] = []  # every goal sent, in order
        self._changed = threading.Condition()
        #: how many messages the server has sent the probe (statuses, begins, responses, feedback, answers)
        self.heard = 0
        #: statuses the transport knows were published and not delivered (a gap in the writer's numbers)
        self.statuses_missed = 0
        #: every log entry's seq heard in feedback, with where among what the link heard it came
        self.log_seqs: list[tuple[int, int]] = []
        #: what the transport found wrong in how a topic (``"status"``, ``"begin"``) is offered, which
        #: no trace carries (DDS: a durability that a transient-local reader cannot match)
        self.offered: dict[str, str] = {}
        #: when the run's ``--deadline`` passes, on :meth:`real_time` (set by the probe as its run
        #: begins, unless the link counts it from earlier): no wait of the link goes past it, and
        #: nothing is asked of the server after it
        self.ends_at = math.inf
        #: the deadline cut the link's waiting on the server short, or kept a request from it: what
        #: was heard since is no verdict on the server
        self.cut_off = False
        #: the server answered the description query once: it offers the query (R16; rmf_ros2 does not, D17)
        self.query_answered = False

    # ---------------------------------------------------------------- the transport's part

    def clock(self) -> float:
        """The link's monotonic time, in seconds."""
        raise NotImplementedError

    def real_time(self) -> float:
        """Real (wall-clock) monotonic time, in seconds, on which ``--deadline`` is counted: the
        link's own clock, where that is real (a link on simulated time keeps real time apart)."""
        return self.clock()

    def time_left(self) -> float:
        """What is left of the run's ``--deadline`` in real time (seconds; below 0 once it passed)."""
        return self.ends_at - self.real_time()

    def wait(self, condition: Callable[[], bool], timeout: float) -> bool:
        """Wait, at most ``timeout`` seconds, until ``condition()`` holds (it is asked under the
        link's lock, after each message heard); whether it holds."""
        raise NotImplementedError

    def wait_for_server(self, timeout: float) -> bool:
        raise NotImplementedError

    def turn(self) -> None:
        """Let the server take what is due now: a link that hands an accepted goal over at its next turn
        (in process, the driver protocol) hands it over; a transport whose server runs on its own has
        nothing to let happen."""
        self.wait(lambda: False, 0)

    def send(self, goal: Goal) -> Exchange:
        """Send ``goal`` as a new goal (a fresh UUID); its response, feedback and answer come to the
        :class:`Exchange`."""
        raise NotImplementedError

    def cancel(self, exchange: Exchange, timeout: float) -> bool | None:
        """Ask for an action-level cancel of ``exchange``'s goal: whether the server accepted it (its
        response lists the goal as canceling), or None when no response came within ``timeout``."""
        raise NotImplementedError

    def describe(self, timeout: float) -> tuple[Any, str]:
        """The description query's answer (R16: ``running``, ``status``, ``description``, ``id``), or
        None and why there is none."""
        raise NotImplementedError

    def late_subscriber(self) -> threading.Event:
        """A subscription to the status topic made now: the event is set once it receives a status
        (what transient-local keeps).  It listens until the link is destroyed."""
        raise NotImplementedError

    #: the link can interrupt and resume the robot's task (:meth:`interrupt`): the cases that do run
    interrupts = False
    #: the transport is a network, whose reliable channels each deliver in order: one message lost
    #: holds back every later one on its channel until it is sent again (DDS, seconds at a time),
    #: while the server's other channels go on
    channels_lag = False

    def interrupt(self) -> str:
        """Interrupt the robot's task (R14: a task input, which no client of the protocol sends): ``""``
        once done, else why this link cannot (then the case that needs it is not run)."""
        return INTERRUPT_UNOFFERED

    def resume(self) -> str:
        """Resume the robot's task (R14.3): ``""`` once done, else why this link cannot."""
        return INTERRUPT_UNOFFERED

    def introspect(self) -> bool:
        """Publish the probe's own goal events where the transport can (ROS 2 introspection)."""
        return False

    def destroy(self) -> None:
        """Release what the transport holds."""

    # ---------------------------------------------------------------- what the transport hears

    def hear_status(self, status: DynamicEventStatus) -> None:
        self._heard("status", lambda: self.statuses.append(status), message=status)

    def hear_begin(self, begin: DynamicEventDescription) -> None:
        self._heard("begin", lambda: self.begins.append(begin), message=begin)

    def hear_response(self, exchange: Exchange, accepted: bool) -> None:
        def update() -> None:
            exchange.accepted = accepted
            exchange.response_heard, exchange.statuses_before_response = self.heard, len(self.statuses)
            exchange.response_at = self.clock()

        self._heard("goal_response", update, goal_uuid=exchange.uuid, accepted=accepted)

    def hear_feedback(self, exchange: Exchange, feedback: Feedback) -> None:
        def update() -> None:
            exchange.feedback.append(feedback)
            self.log_seqs.extend((self.heard, entry.seq) for entry in feedback.logs)

        self._heard("feedback", update, goal_uuid=exchange.uuid, message=feedback)

    def hear_answer(self, exchange: Exchange, status: GoalStatus, result: Result) -> None:
        def update() -> None:
            exchange.answers.append((status, result))
            if exchange.answer_heard is None:
                exchange.answer_heard = self.heard

        self._heard("result", update, goal_uuid=exchange.uuid, status=status, message=result)

    def hear_cancel_response(self, exchange: Exchange, accepted: bool, *, terminated: bool = False) -> None:
        """The response to an action-level cancel of ``exchange``'s goal; ``terminated``: it refused the
        cancel because the goal had terminated when the server took the request."""

        def update() -> None:
            exchange.cancel_found_ended = terminated
            exchange.cancels_heard += 1

        fields = {"goal_uuid": exchange.uuid, "accepted": accepted, "terminated": terminated}
        self._heard("cancel_response", update, **fields)

    def sent(self, kind: str, **fields: Any) -> None:
        """A record of what the probe sends (a goal, a cancel request), for the trace."""
        with self._changed:
            if kind == "cancel_request":
                for made in self.made:
                    if made.uuid == fields["goal_uuid"]:
                        made.cancels_asked += 1
            if self._trace is not None:
                self._trace.observe(kind, **fields)

    def end(self) -> None:
        """The trace's ``end`` record: the probe heard the server out (it waited, within --timeout once
        more, for every response and answer it expected, over a link that showed no loss or lateness);
        what comes after it is not traced."""
        with self._changed:
            if self._trace is not None:
                self._trace.observe("end")
            self._trace = None

    def _heard(self, kind: str, update: Callable[[], None], **fields: Any) -> None:
        with self._changed:
            self.heard += 1
            if self._trace is not None:
                self._trace.observe(kind, **fields)
            update()
            self._changed.notify_all()

    # ---------------------------------------------------------------- what the cases ask

    def mark(self, text: str) -> None:
        """A comment in the trace: what the records after it belong to."""
        with self._changed:
            if self._trace is not None:
                self._trace.comment(text)

    @property
    def status(self) -> DynamicEventStatus | None:
        with self._changed:
            return self.statuses[-1] if self.statuses else None

    def wait_status(
        self, condition: Callable[[DynamicEventStatus], bool], timeout: float
    ) -> DynamicEventStatus | None:
        """The latest status once it satisfies ``condition``, or None after ``timeout`` seconds."""

        matched: list[DynamicEventStatus] = []

        def holds() -> bool:  # asked under the lock: the status that held is the one returned
            if self.statuses and condition(self.statuses[-1]):
                matched.append(self.statuses[-1])
                return True
            return False

        return matched[-1] if self.wait(holds, timeout) else None

    def wait_seen(self, condition: Callable[[DynamicEventStatus], bool], since: int, timeout: float) -> bool:
        """Whether a status received after the first ``since`` satisfies ``condition``, waiting at
        most ``timeout`` seconds (a later status may have followed it)."""
        return self.wait(lambda: any(map(condition, self.statuses[since:])), timeout)

    def wait_begin(self, seq: int, timeout: float) -> bool:
        """Whether the begin of run ``seq`` has come, waiting at most ``timeout`` seconds (the begin
        topic is read apart from the status topic, so a run's begin may follow its status)."""
        return self.wait(lambda: any(begin.dynamic_event_seq == seq for begin in self.begins), timeout)

    def history(self) -> list[DynamicEventStatus]:
        """Every status received so far, oldest first."""
        with self._changed:
            return list(self.statuses)


@attrs.frozen
class Options:
    """What the probe is pointed at and how long it waits."""

    fleet: str
    robot: str
    place: str | None = None
    category: str = "go_to_place"
    #: more places, taken in turn after ``place`` by the NEXTs that send the robot somewhere, so that a
    #: child does not end at once where the robot already stands
    more_places: tuple[str, ...] = ()
    timeout: float = 10.0
    begin_command: str | None = None
    #: commands that interrupt and resume the robot's task (R14), each returning once it took effect:
    #: the interrupt cases run over a link that cannot do it itself (DDS)
    interrupt_command: str | None = None
    resume_command: str | None = None
    known: frozenset[str] = frozenset()
    trace: str | None = None
    stubborn_minimum: float = 2.0
    introspection: bool = False
    #: how long to wait for the robot's server to appear (DDS discovery can take seconds: apart from
    #: the timeout of each wait of a case)
    server_wait: float = 10.0
    #: the command line's ROS arguments (``--ros-args ...``), given to rclpy
    ros_args: tuple[str, ...] = ()
    #: the cases that may be missing without failing the run: ids, globs, sections or rules
    allow_missing: tuple[str, ...] = ()
    #: the cases ``--known`` expects to be missing (:data:`~dynevent.conformance.probe.cases.KNOWN_MISSING`)
    known_missing: frozenset[str] = frozenset()
    #: where to write the JUnit report, and the readable report (HTML when the name ends .html/.htm)
    junit: str | None = None
    report: str | None = None
    #: the bound on the whole run once the server is found (seconds): no wait goes past it
    deadline: float = 120.0


#: How many cases in a row may wait out the timeout, the server sending nothing meanwhile, before the
#: probe takes it as silent and reports the rest as not run (the vector runner stops after three
#: timeouts in a row too).
SILENT_AFTER = 3
#: Why a case of a silence of the action's channel, while the server answered its description query,
#: is not run where its response never came (:func:`_answers_aside`).
HELD_BACK = (
    "the action's responses were held back on the link (the server answered its description query "
    "meanwhile), and this case's never came"
)

#: Why the cases after :data:`SILENT_AFTER` timeouts in a row are not run.
STOPPED_ANSWERING = (
    f"the server stopped answering ({SILENT_AFTER} cases in a row waited out --timeout and heard nothing)"
)

#: Why a case that sends the robot somewhere is not run.
NO_PLACE = "no place to send the robot to: give --place (or begin runs whose estimate names one)"


def _waits_or_ended(status: DynamicEventStatus) -> bool:
    """The robot waits for a NEXT (R20.2 included), or its run has ended."""
    return machine.robot_waits(status) or status.dynamic_state == DynamicState.INACTIVE


class _Unreachable(Exception):
    """A case cannot be carried out: its finding is ``missing``."""


class _TimedOut(_Unreachable):
    """A case cannot be carried out because the server did not show what it waited for in time."""


def _complete(exchange: Exchange) -> bool:
    """The goal has its response and, accepted, its answer, and a NEXT that ran a child its start's
    feedback (R6.4: a lossy link may deliver it after the answer)."""
    if exchange.accepted is False:
        return True
    return (
        exchange.accepted is True
        and bool(exchange.answers)
        and (bool(exchange.feedback) or not _ran_a_child(exchange))
    )


def _ran_a_child(exchange: Exchange) -> bool:
    """A NEXT answered with its child's end (not a failure to begin): its start fed back (R6.4)."""
    answer = exchange.answer
    return (
        exchange.goal.event_type == EventType.NEXT.value
        and answer is not None
        and not answer[1].execution_failure
        and answer[0] is not GoalStatus.CANCELED
    )


def _feedback_lost(link: Link, exchange: Exchange) -> range | None:
    """The log seqs the server numbered while ``exchange``'s child ran that never came, where the
    feedback heard shows such a gap: between the highest seq heard before it was sent and the
    lowest above that heard after its answer (a robot numbers its log entries one by one, R7.3).
    Feedback published and lost on the way (a reliable topic keeps 10 messages: a lossy link
    that repairs slowly loses older ones), rather than never sent."""
    if exchange.answer_heard is None:
        return None
    seqs = link.log_seqs
    before = [seq for heard, seq in seqs if heard <= exchange.sent_heard]
    if not before:
        return None
    low = max(before)
    after = [seq for heard, seq in seqs if heard > exchange.answer_heard and seq > low]
    if not after:
        return None
    high, came = min(after), {seq for _, seq in seqs}
    missing = [seq for seq in range(low + 1, high) if seq not in came]
    return range(missing[0], missing[-1] + 1) if missing else None


def _fails(case: Case, cause: str, expected: str, seen: str, *, divergence: str | None = None) -> CaseFinding:
    """The one way a case's script fails it: for what a trace cannot carry (``cause`` a key of
    :data:`~dynevent.conformance.probe.cases.UNTRACEABLE`; ``"timeout"``, a message that did not come
    in time, marks the finding ``absent``).  Every other failure is the judge's, over the case's
    records (:func:`~dynevent.conformance.probe.cases.judge_verdicts`)."""
    if cause not in probe_cases.UNTRACEABLE:
        raise ValueError(f"cause: not a reason a script fails a case for (got {cause!r})")
    return CaseFinding(
        case, Verdict.FAIL, expected=expected, seen=seen, divergence=divergence, absent=cause == "timeout",
        cause=cause,
    )  # fmt: skip


def _seen_by_script(case: Case, expected: str, seen: str) -> CaseFinding:
    """A case whose script saw what the judge decides: the verdict is the judge's, over the case's
    records (it passes when the judge finds nothing there); ``seen`` says what the script saw."""
    return CaseFinding(case, Verdict.PASS, expected=expected, seen=seen)


def _describe_goal(goal: Goal) -> str:
    return f"sent {goal_text(goal)}"


def _describe_answer(exchange: Exchange) -> str:
    if exchange.accepted is None:
        return "no response"
    if not exchange.accepted:
        return "rejected"
    answer = exchange.answer
    if answer is None:
        return "accepted, no answer yet"
    status, result = answer
    failure = f" {result.execution_failure.splitlines()[0]!r}" if result.execution_failure else ""
    return f"accepted, answered {status.value}{failure} (status {result.status!r}, id {result.id})"


class Probe:
    """Carries out cases over a :class:`Link`; :meth:`run` gives one finding per case."""

    def __init__(self, link: Link, options: Options) -> None:
        self.link = link
        self.options = options
        self.messages: list[str] = []
        self.exchanges: list[Exchange] = []
        #: the cases, one after the other, that waited out the timeout and heard nothing meanwhile
        self.silent_cases: list[str] = []
        #: whether the server had responded to a goal request before those cases fell silent
        self.answered_before_silence = False
        #: whether the server had sent the probe anything (a status, an answer to a query) before them
        self.heard_before_silence = False
        self.silence_waited = False  # a silence was waited out once more (_hear_out_silence) in vain
        #: the cases of a silence the server's description query then showed the link's (_answers_aside)
        self.held_back: list[str] = []
        self.status_waited = False  # the first status was waited for once more (_hear_out_status)
        #: the cases that sent a goal request and heard no response to it
        self.unresponded: set[str] = set()
        self._places_sent = 0
        self._nexts: list[Exchange] = []  # every NEXT sent, across cases: where the robot went
        # the deadline on the link's clock, and in real time (from here, or from where the link began
        # counting it), where the link's clock is simulated
        self.ends_at = link.clock() + options.deadline
        link.ends_at = min(link.ends_at, link.real_time() + options.deadline)
        #: the kinds of wait that have timed out once (``"status"``), and why: the cases that need one
        #: are not run to wait it out again (the cause is said instead)
        self.dead: dict[str, str] = {}
        #: a wait of the case running had less than ``--timeout``: what the deadline left
        self.cut_short = False
        #: each case's goals left without their response or answer when it ended, by case id: the run's
        #: end sees whether it came late
        self.unanswered: dict[str, list[Exchange]] = {}
        #: what a case waited for in vain besides its goals' messages, by case id: whether it came since
        self.heard_later: dict[str, Callable[[], bool]] = {}
        #: the goals a case ended without their response (the server may take them later), in order
        self.given_up: list[Exchange] = []
        #: the same, kept to the run's end (:attr:`given_up` lets go of those waited for once): one whose
        #: response came after all shows the link late, and the run does not say it heard the server out
        self.abandoned: list[Exchange] = []

    @property
    def timeout(self) -> float:
        """The bound on the next wait: ``--timeout``, or what is left of ``--deadline`` when less (the
        case's waits are then cut short: :meth:`run` says so)."""
        left = min(self.ends_at - self.link.clock(), self.link.time_left())
        if left < self.options.timeout:
            self.cut_short = True
        return max(_LEAST_WAIT, min(self.options.timeout, left))

    @property
    def past_deadline(self) -> bool:
        return self.link.clock() >= self.ends_at or self.link.time_left() <= 0

    def blocked(self, case: Case) -> str | None:
        """Why ``case`` is not run: a kind of wait it needs has timed out already, or the deadline passed."""
        if self.past_deadline:
            return f"the run's --deadline of {self.options.deadline:g} s passed"
        for kind, needs in _NEEDS_OF_WAIT.items():
            if kind in self.dead and case.needs in needs:
                _hear_out_status(self)
                if self.link.statuses:
                    del self.dead[kind]  # it came after all: the cases that need a run run
                    continue
                return self.dead[kind]
        return None

    # ---------------------------------------------------------------- carrying out

    def run(self, case: Case) -> CaseFinding:
        self.messages = []
        self.exchanges = []
        self.cut_short = False
        self.link.mark(f"case {case.id}")
        started = self.link.clock()
        heard, earlier = self.link.heard, [made for made in self.link.made if made.accepted is None]
        sent = len(self.link.made)
        self.given_up.extend(made for made in earlier if made not in self.given_up)
        self.abandoned.extend(made for made in earlier if made not in self.abandoned)
        timed_out = False
        try:
            if case.needs in ("child", "place") and self.options.place is None:
                raise _Unreachable(NO_PLACE)
            finding = _CASES[case.id](self, case)
        except _Unreachable as exc:
            finding = CaseFinding(case, Verdict.MISSING, seen=str(exc))
            timed_out = isinstance(exc, _TimedOut)
        # what the verdict lacked, before the waits below: the run's end sees whether it came late
        self.unanswered[case.id] = [exchange for exchange in self.exchanges if not _complete(exchange)]
        finding = self._answered_once(finding)
        # the server had less than --timeout, or was not heard to the end: not its failure
        if (finding.absent and self.cut_short) or self.link.cut_off:
            why = f"{CUT_SHORT.format(deadline=self.options.deadline)} ({finding.seen})"
            finding = CaseFinding(case, Verdict.MISSING, seen=why)
        finding = _unless_earlier_came(finding, earlier, heard)
        # silent: the case waited out the timeout and the server sent nothing at all meanwhile
        silent = (timed_out or finding.absent) and self.link.heard == heard
        if any(exchange.accepted is None for exchange in self.exchanges):
            self.unresponded.add(case.id)
        if silent and not self.silent_cases:
            self.answered_before_silence = any(made.accepted is not None for made in self.link.made[:sent])
            self.heard_before_silence = heard > 0
        self.silent_cases = [*self.silent_cases, case.id] if silent else []
        return self._settled(finding, started)

    def _late_running(self) -> list[Exchange]:
        """The goals accepted after the case that sent them gave up on them (a lossy link delivered
        them late), not answered yet: their child may still run."""
        return [made for made in self.given_up if made.accepted and made.answer_heard is None]

    def _settled(self, finding: CaseFinding, started: float) -> CaseFinding:
        """The finding with the case's messages, time, and whether --known or --allow-missing expect it."""
        case = finding.case
        missing = finding.verdict is Verdict.MISSING
        return attrs.evolve(
            finding,
            messages=tuple(self.messages),
            seconds=self.link.clock() - started,
            known=finding.verdict is Verdict.FAIL and finding.divergence in self.options.known,
            expected_missing=missing
            and (
                case.id in self.options.known_missing or probe_cases.matches(case, self.options.allow_missing)
            ),
        )

    @property
    def silent(self) -> bool:
        """Has the server stopped answering: :data:`SILENT_AFTER` cases in a row waited out the timeout
        with no message from it?"""
        return len(self.silent_cases) >= SILENT_AFTER

    def not_run(self, case: Case, why: str) -> CaseFinding:
        """The finding of a case the probe did not carry out."""
        self.messages = []
        return self._settled(CaseFinding(case, Verdict.MISSING, seen=why), self.link.clock())

    def note(self, text: str) -> None:
        self.messages.append(text)

    def _answered_once(self, finding: CaseFinding) -> CaseFinding:
        """Every goal the case saw accepted, its own and its clean-up's, answered exactly once (R19.1):
        a case that otherwise passed fails when one was not."""
        for exchange in self.exchanges:
            goal = _describe_goal(exchange.goal).removeprefix("sent ")
            if exchange.accepted and not exchange.answered(self.timeout):
                what = f"{goal} accepted, no answer"
            else:  # a goal answered twice is the judge's to find (R19.1), in the case's records
                continue
            self.note(f"{what} within {self.timeout:g} s (R19.1)")
            if finding.verdict in (Verdict.PASS, Verdict.INFO):
                expected = "every accepted goal answered exactly once (R19.1)"
                return _fails(finding.case, "timeout", expected, what)
        return finding

    def waiting(self) -> DynamicEventStatus:
        """The status of an active run the robot waits in, after the begin command when one is given
        and the robot is not waiting; else the case is missing.  Waiting is WAITING, or RUNNING with
        a child's final status (R20.2: what rmf_ros2 keeps publishing after a child ends)."""
        timeout = self.timeout
        late = self._late_running()
        if late:  # a late goal's child may run, though no status heard says so yet: let it end first
            ended = self.link.wait(lambda: all(made.answer_heard is not None for made in late), timeout)
            self.note(f"{goal_text(late[0].goal)}, accepted late, {'was' if ended else 'was not'} answered")
            if not ended:  # waited for once: later cases go by the statuses alone
                self.given_up = [made for made in self.given_up if made not in late]

        def waits(status: DynamicEventStatus) -> bool:  # and not older than what the answers told
            return machine.robot_waits(status) and not _behind(status, self.link.made, self._nexts)

        status = self.link.wait_status(waits, 0.5)
        if status is None and self.options.begin_command:
            self._run_begin_command()
        status = status or self.link.wait_status(waits, timeout)
        if status is None:
            raise _TimedOut(f"no active run (a WAITING status) within {timeout:g} s")
        return status

    def _run_begin_command(self) -> None:
        """Run ``--begin-command``; a command that cannot run makes the case missing, with why."""
        why = _run_command(self, "--begin-command", self.options.begin_command or "")
        if why:
            raise _Unreachable(why)

    def any_status(self) -> DynamicEventStatus:
        status = self.link.wait_status(lambda s: True, self.timeout)
        if status is None:
            raise _TimedOut(f"no status within {self.timeout:g} s")
        return status

    def send(self, goal: Goal, *, answer: bool = True) -> Exchange:
        """Send ``goal``; wait for the response and, when accepted and ``answer``, for its answer."""
        exchange = self.link.send(goal)
        self.exchanges.append(exchange)
        if goal.event_type == EventType.NEXT.value:
            self._nexts.append(exchange)
        self.note(_describe_goal(goal))
        if not exchange.responded(self.timeout):
            self.note("no response")
            return exchange
        if answer and exchange.accepted:
            self.answered(exchange)
        self.note(_describe_answer(exchange))
        return exchange

    def answered(self, exchange: Exchange) -> bool:
        """Wait for the goal's answer and, when it says a child ran, for the feedback of its start
        (R6.4), which another channel may bring after the answer; whether the answer came."""
        if not exchange.answered(self.timeout):
            return False
        if _ran_a_child(exchange):
            exchange.wait(lambda: bool(exchange.feedback), self.timeout)
        return True

    def cancel(self, exchange: Exchange) -> bool | None:
        """An action-level cancel of ``exchange``'s goal: accepted, refused, or None (no response)."""
        accepted = self.link.cancel(exchange, self.timeout)
        outcome = {None: "no response", True: "accepted", False: "refused"}[accepted]
        if exchange.cancel_found_ended:
            outcome += " as of a goal already terminated"
        self.note(
            f"sent an action-level cancel of {_describe_goal(exchange.goal).removeprefix('sent ')}: {outcome}"
        )
        return accepted

    def next_goal(self, status: DynamicEventStatus, goal_id: int | None = None) -> Goal:
        if self.options.place is None:
            raise _Unreachable(NO_PLACE)
        places = (self.options.place, *self.options.more_places)
        place = places[self._places_sent % len(places)]
        self._places_sent += 1
        if place == self._standing_at() and len(places) > 1:  # a child there would end at once
            place = places[self._places_sent % len(places)]
            self._places_sent += 1
        return Goal(
            dynamic_event_seq=status.dynamic_event_seq,
            event_type=EventType.NEXT,
            category=self.options.category,
            description=json.dumps({"one_of": [place]}),
            id=_fresh(status.id) if goal_id is None else goal_id,
        )

    def _standing_at(self) -> str | None:
        """The place the robot was last sent to and reached (its NEXT answered ``completed``), as far
        as the probe's own goals tell; None when none did."""
        for exchange in reversed(self._nexts):
            answer = exchange.answer
            if answer is not None and answer[1].status == Status.COMPLETED.value:
                try:
                    places = json.loads(exchange.goal.description).get("one_of") or [None]
                except (ValueError, AttributeError):
                    return None
                return str(places[0])
        return None

    def refused(self, case: Case, goal: Goal) -> CaseFinding:
        """A case whose goal the spec refuses: the judge finds it accepted in the case's records (its
        rule, its D-number); no response within the timeout is the script's failure.  A case whose
        failure a trace does not show (a refusal the server's configuration decides) fails by the
        script when the goal is accepted."""
        exchange = self.send(goal)
        if exchange.accepted is None:
            return _fails(case, "timeout", "rejected", "no response")
        seen = _describe_answer(exchange)
        if exchange.accepted and not case.trace_shows_failure:
            return _fails(case, "configuration", "rejected", seen)
        return _seen_by_script(case, "rejected", seen)

    def _running_child(
        self, goal: Goal, status: DynamicEventStatus, exchange: Exchange
    ) -> DynamicEventStatus | None:
        """The status that shows the child of ``goal`` running (the NEXT's id, or a new one the
        server gave it, D10), or None when the NEXT was answered first or ``--timeout`` passed."""

        def new_child(s: DynamicEventStatus) -> bool:
            return (
                machine.runs_a_child(s)
                and s.dynamic_event_seq == goal.dynamic_event_seq
                and (s.id == goal.id or s.id > status.id)
            )

        deadline = self.link.clock() + self.timeout
        while self.link.clock() < deadline:
            running = self.link.wait_status(new_child, min(_LOOK_AGAIN, deadline - self.link.clock()))
            if running is not None:
                return running
            if exchange.answers:
                return None
        return None

    @contextmanager
    def child(self) -> Iterator[tuple[Exchange, int]]:
        """A running child (its NEXT accepted and the status RUNNING with a new child); cancelled after.
        The child's id is the one the status names: the NEXT's own where the server follows R6.2, the
        server's where it numbers children itself (D10), as a client that keeps no state reads it."""
        places = 1 + len(self.options.more_places)
        for tried in range(1, places + 1):
            status = self.waiting()
            goal = self.next_goal(status)
            exchange = self.send(goal, answer=False)
            if not exchange.accepted:
                raise _Unreachable(f"the NEXT that should run a child was {_describe_answer(exchange)}")
            running = self._running_child(goal, status, exchange)
            if running is not None:
                break
            if not exchange.answers:
                raise _TimedOut(f"the child of NEXT {goal.id} never showed RUNNING within {self.timeout:g} s")
            # answered before a status showed it running: the robot stood where it was sent, or the
            # link delivered the answer before the status (a lossy link: a longer child lets it run)
            self.note(f"the child of NEXT {goal.id} was answered before a status showed it running "
                      f"({_describe_answer(exchange)})")  # fmt: skip
            if tried == places:
                raise _Unreachable(ENDED_UNSEEN.format(places=places))
            self.link.wait_status(_waits_or_ended, self.timeout)
        assert running is not None  # every way out of the loop but its break raised
        if running.id != goal.id:
            self.note(f"the server numbered the child {running.id} (the NEXT's id was {goal.id})")
        try:
            yield exchange, running.id
        finally:
            self.stop_unanswered(exchange, running.id)

    def stop_unanswered(self, exchange: Exchange, child: int | None = None) -> None:
        """After a case: a NEXT not yet answered has its child (``child``, else the one a status shows
        running) stopped by a CANCEL; then the robot waits, or its run has ended."""
        if not exchange.answers:
            status = self.link.wait_status(machine.runs_a_child, self.timeout) if child is None else None
            child = child if status is None else status.id
            if child is not None:
                goal = exchange.goal
                stop = Goal(dynamic_event_seq=goal.dynamic_event_seq, event_type=EventType.CANCEL, id=child)
                self.send(stop)
                exchange.answered(self.timeout)
        self.link.wait_status(_waits_or_ended, self.timeout)


#: The least time a command of the probe's (``--begin-command``, ``--interrupt-command``,
#: ``--resume-command``) is given, in seconds, whatever ``--timeout``: a command that is a ROS 2
#: process of its own starts and discovers the server before it does anything (``dynevent task``:
#: about 3 s on one host).
COMMAND_BOUND = 15.0

#: Why a case that interrupts the robot's task is not run over a link that cannot (an interruption is
#: the task's, and no client of the protocol sends one).
INTERRUPT_UNOFFERED = (
    "this link cannot interrupt the robot's task (a task input no client sends; over ROS 2, "
    "--interrupt-command and --resume-command do)"
)
#: The shortest wait the deadline leaves (seconds): a message already on its way is still read.
_LEAST_WAIT = 0.05
#: Why a case whose wait the deadline cut short is not run: what it waited for might have come
#: within ``--timeout``, so the case is no verdict on the server.
CUT_SHORT = "not run to its end: the run's --deadline of {deadline:g} s cut its wait short; raise --deadline"
#: Why a case that needs a running child is not run when no child was seen running before its answer.
ENDED_UNSEEN = (
    "at each of the {places} place(s) given, the child was answered before a status showed it running: "
    "the robot stood there, or the link was slower than the child (children that take longer let it run)"
)
#: Why ``action.cancel_running`` (or ``action.cancel_queued``) is not run when the server refused its
#: cancel as of a goal already terminated: the child ended before the cancel reached the server (found
#: in the lab, where the robot stood at its place already, and the case reported the refusal as D31).
CANCEL_AFTER_END = (
    "the child ended before the cancel reached the server, which refused it as of a goal already "
    "terminated (rightly, R10.5): a child that takes longer lets the case run"
)
#: Why ``action.cancel_waiting`` is not run when the server refused its cancel as of a goal already
#: terminated: the CANCEL had ended first (found in the lab: the deployed adapter answers a CANCEL as
#: soon as it has told the child to stop, D1).
CANCEL_ENDED = (
    "the CANCEL had ended before its cancel reached the server, which refused it as of a goal already "
    "terminated (rightly, R10.5): it waits for the child's next report, which came sooner than this link "
    "brought its acceptance (children that report less often let the case run), or it waited for "
    "nothing (rmf_ros2 answers a CANCEL as soon as it has told the child to stop, D1)"
)
#: Why ``finished.ends_the_run`` is not run when the next run's status came, the INACTIVE did not, and
#: the transport knows a status was published and not delivered meanwhile.
OVERWRITTEN = (
    "run {later}'s status came and run {seq}'s INACTIVE did not, and a status was published that never "
    "came: the status topic keeps one message, and the next run's took its place before this link "
    "delivered it (a lossy link)"
)
#: Why ``describe.after_the_run`` is not run when the next run began before its query reached the server.
BEGAN_FIRST = (
    "run {later} began after run {ended} ended and before the description query could be asked{seen}: "
    "the server begins runs again sooner than this link brings a run's end"
)
#: Why a case whose goal was sent while a late status showed a child running is not run.
ENDED_FIRST = (
    "child {child} had ended when the goal reached the server (its statuses say so): the status the "
    "probe went by came late (a lagging link; children that take longer let the case run)"
)
#: Why ``cancel.both_answered`` is not run when a CANCEL was refused only after the child's end was heard.
REFUSED_AFTER_END = (
    "a CANCEL of child {child} was refused after the probe heard the child end: it may have reached the "
    "server after that end (a lossy link sends a lost request again, late), where the refusal is right "
    "(R4.13); the case needs both CANCELs to reach the server while the child runs"
)
#: Why a case that lacked a goal's feedback is not run when the log seqs heard show it published and lost.
FEEDBACK_LOST = (
    "feedback published while its child ran never came: the log entries heard skip seq {first} to {last} "
    "(a reliable topic keeps its last 10 messages, and a lossy link that repairs slowly loses older ones)"
)
#: Why a case that failed by what it saw is not run when an earlier case's goal took effect meanwhile.
EARLIER_CAME = (
    "an earlier case's goal ({goal}), whose response had not come when this case began, was accepted "
    "during it (a lossy link delivered it late): what this case saw may be its doing"
)
#: Why a case that waited in vain is not run over a link that lost or delayed messages during the run.
LOSSY = (
    "what it waited for never came, over a link that lost messages during the run ({lost}): no verdict "
    "on the server (probe it over a link that loses none)"
)
#: Why feedback.log_seq, failed for log seqs that skip within a child, is not run over a link that
#: lost messages: feedback lost on the way leaves them so (the judge reads them so too, uncertain).
LOSSY_LOGS = (
    "log seqs that skip within a child, over a link that lost messages during the run ({lost}): feedback "
    "lost on the way leaves them so; no verdict on the server (probe it over a link that loses none)"
)
#: Why cancel.both_answered, failed for a CANCEL refused while the probe had not heard the child end,
#: is not run over a link that lost messages: its channels lag one another by seconds there, and the
#: request may have reached the server after the child's end, where the refusal is right (R4.13).
LOSSY_REFUSAL = (
    "a CANCEL refused, over a link that lost messages during the run ({lost}): its request may have "
    "reached the server after the child's end, where the refusal is right (R4.13), and the end came "
    "late; no verdict on the server (probe it over a link that loses none)"
)
#: Why a case whose awaited message came after ``--timeout`` is not run: the link, not the server.
LATE = "not run to its end: what it waited for came after --timeout's {timeout:g} s; raise --timeout"
#: Which cases a kind of wait that timed out stops: no status heard stops every case that needs an
#: active run (the begin command each would run cannot make a status heard that none was).
_NEEDS_OF_WAIT = {"status": ("run", "place", "child")}

#: How often a wait for a running child looks whether its NEXT was answered first (seconds).
_LOOK_AGAIN = 0.2


def _behind(status: DynamicEventStatus, made: list[Exchange], nexts: list[Exchange]) -> bool:
    """A status of a run a FINISHED among the goals ``made`` ended, or one that names an id below a
    child whose answer ``nexts`` has: it was published before those answers, which another channel
    brought first (a lagging link), and a goal built from it would name an ended run or a stale id."""
    seq = status.dynamic_event_seq
    if any(  # the run ended: the probe's FINISHED of it succeeded
        exchange.goal.event_type == EventType.FINISHED.value
        and exchange.goal.dynamic_event_seq == seq
        and exchange.answer is not None
        and exchange.answer[0] is GoalStatus.SUCCEEDED
        for exchange in made
    ):
        return True
    ids = [  # the children the answers name (a feedback's id is the server's word less firmly)
        answer[1].id
        for exchange in nexts
        if exchange.goal.dynamic_event_seq == seq
        for answer in exchange.answers[:1]
        if not answer[1].execution_failure
    ]
    return bool(ids) and not id_not_after(max(ids), status.id)


def _unless_earlier_came(finding: CaseFinding, earlier: list[Exchange], heard: int) -> CaseFinding:
    """A case failed by what it saw, while a goal an earlier case sent, whose response had not come
    when this one began, was accepted meanwhile: that goal reached the server late (a lossy link sent
    it again), and what this case saw may be its doing, so the case is not run, saying so.  (One
    accepted before this case began is waited for by :meth:`Probe.waiting`.)"""
    came = [made for made in earlier if made.accepted and (made.response_heard or 0) > heard]
    if finding.absent or not came:
        return finding
    why = EARLIER_CAME.format(goal=goal_text(came[0].goal))
    if finding.verdict in (Verdict.PASS, Verdict.INFO):  # the judge's verdict meets the doubt
        return attrs.evolve(finding, doubt=why)
    if finding.verdict is not Verdict.FAIL:
        return finding
    return attrs.evolve(finding, verdict=Verdict.MISSING, seen=f"{why} ({finding.seen})", by_link=True)


def _feedback_lost_in(probe: Probe, finding: CaseFinding) -> range | None:
    """The log seqs lost on the way while a goal of ``finding``'s case ran, where every goal the
    case left unanswered has come whole since but for that feedback (:func:`_feedback_lost`)."""
    lost = None
    for exchange in probe.unanswered.get(finding.case.id, []):
        if _complete(exchange):
            continue
        gap = _feedback_lost(probe.link, exchange) if exchange.accepted and exchange.answers else None
        if gap is None:
            return None
        lost = lost or gap
    return lost


# -------------------------------------------------------------------- the cases


def _status_latched(probe: Probe, case: Case) -> CaseFinding:
    expected = "a late subscriber receives the status"
    offered = probe.link.offered.get("status")
    if offered is not None:  # what the transport saw of the topic: no trace carries it
        probe.note(f"the status topic is {offered}")
        return _fails(case, "transport", expected, f"the status topic is {offered}")
    if probe.link.wait_status(lambda status: True, probe.timeout) is None:
        # a server with no transient-local status (a volatile one never matches this subscriber), or a
        # lossy link that delivers it later
        probe.heard_later[case.id] = lambda: bool(probe.link.statuses)
        return _fails(case, "timeout", expected, f"no status within {probe.timeout:g} s")
    heard = probe.link.late_subscriber()
    if probe.link.wait(heard.is_set, probe.timeout):
        return CaseFinding(case, Verdict.PASS, expected="a status", seen="a status")
    probe.heard_later[case.id] = heard.is_set  # a lossy link: matched, or delivered to, late
    return _fails(case, "timeout", expected, f"nothing within {probe.timeout:g} s")


def _status_waiting(probe: Probe, case: Case) -> CaseFinding:
    status = probe.waiting()
    seq = status.dynamic_event_seq
    begins = [begin.dynamic_event_seq for begin in probe.link.begins]
    probe.note(f"status {status_text(status)}; begins seen for runs {begins}")
    expected = "WAITING, standby, begun"
    if status.status != _STANDBY:  # the judge finds the status the machine's state has not (R2.2)
        return _seen_by_script(case, expected, f"WAITING, {status.status}")
    if seq not in begins:
        # the begin topic is another channel than the status's: over a lossy link, it may come later
        def begun() -> bool:
            return any(begin.dynamic_event_seq == seq for begin in probe.link.begins)

        if not probe.link.wait(begun, probe.timeout):
            probe.heard_later[case.id] = begun
            seen = f"begins for {begins} within {probe.timeout:g} s"
            return _fails(case, "timeout", f"a begin for run {seq}", seen)
    return CaseFinding(case, Verdict.PASS, expected=expected, seen="so")


def _goal(status: DynamicEventStatus, event_type: int, **values: Any) -> Goal:
    fields: dict[str, Any] = {
        "dynamic_event_seq": status.dynamic_event_seq,
        "event_type": event_type,
        "id": 0,
    }
    fields.update(values)
    return Goal(**fields)


def _seq_stale(probe: Probe, case: Case) -> CaseFinding:
    status = probe.waiting()
    goal = _goal(status, EventType.FINISHED, dynamic_event_seq=(status.dynamic_event_seq - 1) % _U32)
    return probe.refused(case, goal)


def _seq_future(probe: Probe, case: Case) -> CaseFinding:
    status = probe.waiting()
    goal = _goal(status, EventType.FINISHED, dynamic_event_seq=machine.next_seq(status.dynamic_event_seq))
    return probe.refused(case, goal)


def _event_type_0(probe: Probe, case: Case) -> CaseFinding:
    return probe.refused(case, _goal(probe.waiting(), 0))


def _event_type_unknown(probe: Probe, case: Case) -> CaseFinding:
    return probe.refused(case, _goal(probe.waiting(), 4))


def _category_unknown(probe: Probe, case: Case) -> CaseFinding:
    status = probe.waiting()
    goal = _goal(status, EventType.NEXT, category="dynevent_probe_no_such_category", description="{}",
                 id=_fresh(status.id))  # fmt: skip
    return probe.refused(case, goal)


def _description_not_json(probe: Probe, case: Case) -> CaseFinding:
    status = probe.waiting()
    goal = _goal(status, EventType.NEXT, category=probe.options.category, description="{not json",
                 id=_fresh(status.id))  # fmt: skip
    return probe.refused(case, goal)


#: For each of the field's categories, a description that fits no form of its schema (R4.18): a key
#: of the category's with a value of the wrong type, the slip a client makes most.
UNFIT_DESCRIPTIONS: dict[str, dict[str, Any]] = {
    "go_to_place": {"one_of": 5},
    "perform_action": {"category": 5, "description": {}},
    "sequence": {"activities": 5},
    "clean": {"zone": 5},
    "pickup": {"place": 0, "handler": 5, "payload": []},
    "dropoff": {"place": 0, "handler": 5, "payload": []},
}


def _description_invalid(probe: Probe, case: Case) -> CaseFinding:
    category = probe.options.category
    unfit = UNFIT_DESCRIPTIONS.get(category)
    if unfit is None:  # a category of the server's own: its forms are the server's to say
        raise _Unreachable(f"the probe's category {category!r} is none of the field's, whose schemas bind "
                           f"every server (R4.18): {', '.join(UNFIT_DESCRIPTIONS)}")  # fmt: skip
    status = probe.waiting()
    goal = _goal(
        status, EventType.NEXT, category=category, description=json.dumps(unfit), id=_fresh(status.id)
    )
    return probe.refused(case, goal)


def _stubborn_nan(probe: Probe, case: Case) -> CaseFinding:
    goal = attrs.evolve(probe.next_goal(probe.waiting()), stubborn_period=math.nan)
    return probe.refused(case, goal)


def _cancel_idle(probe: Probe, case: Case) -> CaseFinding:
    status = probe.waiting()
    return probe.refused(case, _goal(status, EventType.CANCEL, id=status.id))


def _runs_a_child(probe: Probe, case: Case) -> CaseFinding:
    status = probe.waiting()
    goal = probe.next_goal(status)
    exchange = probe.send(goal)
    expected = f"accepted; feedback for id {goal.id}; succeeded, completed, id {goal.id}"
    unrun = _not_run(case, exchange, expected)
    if unrun is not None:
        return unrun
    ids = sorted({feedback.id for feedback in exchange.feedback})
    probe.note(f"feedback: {len(exchange.feedback)} message(s), ids {ids}")
    answer = exchange.answer
    if answer is None:
        return _fails(case, "timeout", expected, f"no answer within {probe.timeout:g} s")
    seen = f"feedback ids {ids}; {_describe_answer(exchange)}"
    if not _complete(exchange):  # its start's feedback never came
        return _fails(case, "timeout", expected, seen)
    # the child's ids, its feedback and its answer: the judge's, on the case's records (R6.2, R7.1, R8.1)
    return _seen_by_script(case, expected, seen)


def _not_run(case: Case, exchange: Exchange, expected: str) -> CaseFinding | None:
    """The failure of a NEXT that should have run a child and was not accepted: no response in time,
    or refused, which only the server's configuration could explain (a trace lacks it); else None."""
    if exchange.accepted is None:
        return _fails(case, "timeout", expected, "no response")
    if not exchange.accepted:
        return _fails(case, "configuration", expected, _describe_answer(exchange))
    return None


def _id_stale(probe: Probe, case: Case) -> CaseFinding:
    status = probe.waiting()
    goal = probe.next_goal(status, goal_id=status.id)  # not above the run's highest id
    if status.id == 0:
        raise _Unreachable("the run's highest id is 0: no stale id exists")
    return probe.refused(case, goal)


def _status_after_child(probe: Probe, case: Case) -> CaseFinding:
    try:
        status = probe.waiting()
    except _TimedOut:  # no WAITING status: it fails here when a child's end never published one
        unpublished = _end_unpublished(probe, case)
        if unpublished is None:
            raise
        return unpublished
    child, after = _child_ended(probe, status)
    if after is None:
        return _fails(case, "timeout", f"WAITING, id {child}", "no status after the child")
    probe.note(f"status {status_text(after)}")
    if after.dynamic_state == DynamicState.WAITING and after.status == _STANDBY:
        return CaseFinding(case, Verdict.PASS, expected=f"WAITING, standby, id {child}", seen="so")
    divergence = "D2" if after.dynamic_state == DynamicState.RUNNING else None
    return _fails(case, "status_after_end", f"WAITING, standby, id {child}", f"status {status_text(after)}",
                  divergence=divergence)  # fmt: skip


def _child_ended(probe: Probe, status: DynamicEventStatus) -> tuple[int, DynamicEventStatus | None]:
    """A child run to its end from ``status``: its id, and the status that shows it ended (its id, no
    longer underway), or None when none came within the timeout."""
    goal = probe.next_goal(status)
    exchange = probe.send(goal)
    if not exchange.answers:
        raise _TimedOut(f"the child did not end within {probe.timeout:g} s")
    answer = exchange.answer
    child = answer[1].id if answer is not None and answer[1].id else goal.id  # R8.1: the result names it
    return child, probe.link.wait_status(lambda s: s.id == child and s.status != _UNDERWAY, probe.timeout)


def _end_unpublished(probe: Probe, case: Case) -> CaseFinding | None:
    """R8.4's failure (R2.3: the status changed at the child's end, and must be published) when the
    latest status, of the run of a child whose NEXT (an earlier case's) was answered with its end,
    still shows that child running, or names an id before it (no status came at its start nor at its
    end); None otherwise."""
    latest = probe.link.status
    if latest is None:
        return None
    for exchange in reversed(probe._nexts):
        answer = exchange.answer
        if (
            answer is None
            or answer[1].execution_failure
            or exchange.goal.dynamic_event_seq != latest.dynamic_event_seq
        ):
            continue
        child = answer[1].id
        running = machine.runs_a_child(latest) and child == latest.id
        if not (running or (latest.id != child and id_not_after(latest.id, child))):
            return None

        def published() -> bool:  # a status that shows the child's end, come late (a lagging link)
            status = probe.link.status
            return (
                status is not None
                and not _behind(status, probe.link.made, probe._nexts)
                and machine.robot_waits(status)
            )

        probe.heard_later[case.id] = published
        seen = f"child {child} was answered {answer[1].status!r}; the status still says {status_text(latest)}"
        return _fails(case, "timeout", f"WAITING, standby, id {child} (R8.4, published: R2.3)", seen)
    return None


def _busy(probe: Probe, case: Case) -> CaseFinding:
    with probe.child() as (_, child_id):
        status = probe.link.status or probe.any_status()
        goal = probe.next_goal(status, goal_id=_fresh(child_id))
        finding = probe.refused(case, goal)
        return _unless_ended_first(
            probe, finding, child_id, lambda s: machine.runs_a_child(s) and s.id != child_id
        )


def _busy_finished(probe: Probe, case: Case) -> CaseFinding:
    with probe.child() as (_, child_id):
        status = probe.link.status or probe.any_status()
        finding = probe.refused(case, _goal(status, EventType.FINISHED))
        ended = status.dynamic_event_seq
        return _unless_ended_first(
            probe,
            finding,
            child_id,
            lambda s: s.dynamic_event_seq == ended and s.dynamic_state == DynamicState.INACTIVE,
        )


def _unless_ended_first(
    probe: Probe, finding: CaseFinding, child_id: int, took_effect: Callable[[DynamicEventStatus], bool]
) -> CaseFinding:
    """A goal sent while a status showed ``child_id`` running, and accepted where the spec refuses it
    (which the judge then finds): when the server's own stamps show the child's end before the goal
    took effect (the status whose ``time`` says the child ended, before the one that shows the goal's
    effect), the status the probe went by was late (a lagging link) and the case is not run, with
    why, rather than failed."""
    if finding.verdict is Verdict.MISSING or not probe.exchanges or not probe.exchanges[-1].accepted:
        return finding
    probe.link.wait(lambda: any(took_effect(s) for s in probe.link.history()), probe.timeout)
    history = probe.link.history()
    running = next((n for n, s in enumerate(history) if machine.runs_a_child(s) and s.id == child_id), None)
    if running is None:
        return finding
    end = next((s for s in history[running:] if not (machine.runs_a_child(s) and s.id == child_id)), None)
    effect = next((s for s in history[running:] if took_effect(s)), None)
    if end is None or effect is None or _instant(effect) < _instant(end):
        return finding
    probe.note(f"the server's statuses: child {child_id} ended at {_instant(end)}, the goal took effect "
               f"at {_instant(effect)}")  # fmt: skip
    return CaseFinding(finding.case, Verdict.MISSING, seen=ENDED_FIRST.format(child=child_id), by_link=True)


def _instant(status: DynamicEventStatus) -> int:
    """When the server stamped ``status``, in nanoseconds."""
    return status.time.sec * 1_000_000_000 + status.time.nanosec


def _cancel_wrong_id(probe: Probe, case: Case) -> CaseFinding:
    with probe.child() as (_, child_id):
        status = probe.link.status or probe.any_status()
        other = _within_ids(child_id + 1000)
        return probe.refused(case, _goal(status, EventType.CANCEL, id=other))


def _cancel_running_child(probe: Probe, case: Case) -> CaseFinding:
    expected = "CANCEL succeeded; the NEXT answered once, its child canceled"
    with probe.child() as (running, child_id):
        status = probe.link.status or probe.any_status()
        since = len(probe.link.history())
        cancel = probe.send(_goal(status, EventType.CANCEL, id=child_id))
        running.answered(probe.timeout)
        probe.note(f"the NEXT: {_describe_answer(running)}")
        cancel_answer, next_answer = cancel.answer, running.answer
        if cancel_answer is None or next_answer is None:
            return _fails(case, "timeout", expected, "a goal left without an answer")
        # how each goal was answered is the judge's (R8.2, R8.3; a goal answered twice, R19.1); that
        # the child ended as its robot ends a child it was told to stop is not on the wire
        if next_answer[1].status != _CANCELED:
            seen = f"CANCEL {_describe_answer(cancel)}; NEXT {_describe_answer(running)}"
            return _fails(case, "robot", expected, seen)
        return _status_after_cancel(probe, case, child_id, since)


def _status_after_cancel(probe: Probe, case: Case, child_id: int, since: int) -> CaseFinding:
    """R8.4: once a cancelled child has ended, the status says WAITING ``standby`` with its id.  A
    status after the CANCEL that shows the robot waiting otherwise (rmf_ros2's WAITING ``canceled``,
    D28) is the judge's (R2.2); one that shows the child RUNNING with its end (D2) is what a trace
    cannot tell from a report the child made before its end (``status_after_end``)."""
    expected = f"WAITING, standby, id {child_id}"

    def shows_the_end(status: DynamicEventStatus) -> bool:
        return status.id == child_id and machine.robot_waits(status)

    if not probe.link.wait_seen(shows_the_end, since, probe.timeout):
        return _fails(case, "timeout", expected, "no status after the child")
    for after in filter(shows_the_end, probe.link.history()[since:]):
        if after.dynamic_state == DynamicState.WAITING and after.status == _STANDBY:
            continue
        probe.note(f"status {status_text(after)}")
        if after.dynamic_state != DynamicState.RUNNING:
            return _seen_by_script(case, expected, f"status {status_text(after)}")
        return _fails(case, "status_after_end", expected, f"status {status_text(after)}", divergence="D2")
    return CaseFinding(case, Verdict.PASS, expected=expected, seen="so")


def _finished(probe: Probe, case: Case) -> CaseFinding:
    status = probe.waiting()
    since = len(probe.link.history())
    exchange = probe.send(_goal(status, EventType.FINISHED))
    expected = "succeeded, completed; then INACTIVE"
    answer = exchange.answer
    if answer is None or (answer[0], answer[1].status) != (GoalStatus.SUCCEEDED, _COMPLETED):
        if answer is None and exchange.accepted is not False:  # no response, or no answer yet
            return _fails(case, "timeout", expected, _describe_answer(exchange))
        # refused (R4.16: it passes every check), or answered other than the run's end (R11.1): the judge's
        return _seen_by_script(case, expected, _describe_answer(exchange))
    seq = status.dynamic_event_seq
    missed = probe.link.statuses_missed
    if not probe.link.wait_seen(
        lambda s: s.dynamic_state == DynamicState.INACTIVE and s.dynamic_event_seq == seq,
        since,
        probe.timeout,
    ):
        later = [s for s in probe.link.history()[since:] if seq_after(s.dynamic_event_seq, seq)]
        if later and probe.link.statuses_missed > missed:  # the next run's took the INACTIVE's place
            why = OVERWRITTEN.format(seq=seq, later=later[0].dynamic_event_seq)
            return CaseFinding(case, Verdict.MISSING, seen=why, by_link=True)
        return _fails(case, "timeout", expected, "no INACTIVE status")
    return CaseFinding(case, Verdict.PASS, expected=expected, seen="so")


def _ended(probe: Probe) -> DynamicEventStatus:
    """The status of a run that has ended: the latest, or the last INACTIVE one seen, or the run the
    probe's FINISHED ended when its INACTIVE status never reached the probe (the status topic keeps
    one message, and the next run's may take its place first)."""
    status = probe.any_status()
    if status.dynamic_state != DynamicState.INACTIVE:
        ended = [s for s in probe.link.statuses if s.dynamic_state == DynamicState.INACTIVE]
        finished = [
            exchange.goal.dynamic_event_seq
            for exchange in probe.link.made
            if exchange.goal.event_type == EventType.FINISHED.value
            and exchange.answer is not None
            and exchange.answer[0] is GoalStatus.SUCCEEDED
        ]
        if ended:
            status = ended[-1]
        elif finished:
            status = DynamicEventStatus(dynamic_event_seq=finished[-1], dynamic_state=DynamicState.INACTIVE)
        else:
            raise _Unreachable("no run has ended (no INACTIVE status seen)")
    return status


def _next_after(probe: Probe, case: Case) -> CaseFinding:
    # a NEXT the server would run but for R4.3: a server that refuses it only for its description
    # would pass a NEXT without a place
    return probe.refused(case, probe.next_goal(_ended(probe)))


def _cancel_after(probe: Probe, case: Case) -> CaseFinding:
    status = _ended(probe)
    return probe.refused(case, _goal(status, EventType.CANCEL, id=status.id))


def _finished_after(probe: Probe, case: Case) -> CaseFinding:
    return probe.refused(case, _goal(_ended(probe), EventType.FINISHED))


def _seq_stale_next(probe: Probe, case: Case) -> CaseFinding:
    status = probe.waiting()
    goal = attrs.evolve(probe.next_goal(status), dynamic_event_seq=(status.dynamic_event_seq - 1) % _U32)
    return probe.refused(case, goal)


def _seq_future_next(probe: Probe, case: Case) -> CaseFinding:
    status = probe.waiting()
    goal = attrs.evolve(probe.next_goal(status), dynamic_event_seq=machine.next_seq(status.dynamic_event_seq))
    return probe.refused(case, goal)


def _cancel_seq(probe: Probe, case: Case, seq_of: Callable[[int], int]) -> CaseFinding:
    """A CANCEL naming the running child, but for another run than the child's."""
    with probe.child() as (_, child_id):
        status = probe.link.status or probe.any_status()
        seq = seq_of(status.dynamic_event_seq)
        return probe.refused(case, _goal(status, EventType.CANCEL, id=child_id, dynamic_event_seq=seq))


def _cancel_seq_stale(probe: Probe, case: Case) -> CaseFinding:
    return _cancel_seq(probe, case, lambda seq: (seq - 1) % _U32)


def _cancel_seq_future(probe: Probe, case: Case) -> CaseFinding:
    return _cancel_seq(probe, case, machine.next_seq)


def _ran(exchange: Exchange, child_id: int) -> str | None:
    """None when ``exchange``'s NEXT ran child ``child_id`` to its end (feedback with that id only,
    answered succeeded, completed, with it); else what was seen instead."""
    if not exchange.accepted or exchange.answer is None:
        return _describe_answer(exchange)
    ids = sorted({feedback.id for feedback in exchange.feedback})
    status, result = exchange.answer
    if ids != [child_id] or (status, result.status, result.id) != (
        GoalStatus.SUCCEEDED,
        _COMPLETED,
        child_id,
    ):
        return f"feedback ids {ids}; {_describe_answer(exchange)}"
    return None


def _ran_finding(probe: Probe, case: Case, exchange: Exchange, child_id: int, expected: str) -> CaseFinding:
    """The case passes where the NEXT ran child ``child_id`` to its end; a child seen whole otherwise
    (another id, another answer) is the judge's to fail, on the case's records (R6.2, R6.4, R8.1: a
    server that numbers children itself is labelled D10 there).  Seen in part, the case is not run."""
    seen = _ran(exchange, child_id)
    if seen is None:
        return CaseFinding(case, Verdict.PASS, expected=expected, seen="so")
    if exchange.accepted is True and _complete(exchange):
        return _seen_by_script(case, expected, seen)
    unrun = _not_run(case, exchange, expected) if exchange.accepted is not True else None
    if unrun is not None:
        return unrun
    # seen in part (no answer, or a child that ran without its start's feedback): the run's end tells a
    # server that never sent the rest from a link that delivered it late
    return _fails(case, "timeout", expected, seen)


def _id_zero(probe: Probe, case: Case) -> CaseFinding:
    status = probe.waiting()
    child_id = machine.next_child_id(Goal(id=0), status.id, _SERVER_NUMBERS)
    exchange = probe.send(probe.next_goal(status, goal_id=0))
    return _ran_finding(probe, case, exchange, child_id, f"child {child_id} runs and completes")


def _id_chosen(probe: Probe, case: Case) -> CaseFinding:
    status = probe.waiting()
    chosen = status.id + 5
    if chosen > U64_MAX:
        raise _Unreachable(f"no id above {status.id} is left to choose")
    exchange = probe.send(probe.next_goal(status, goal_id=chosen))
    return _ran_finding(probe, case, exchange, chosen, f"child {chosen} (the NEXT's id) runs and completes")


def _stateless_id(probe: Probe, case: Case) -> CaseFinding:
    status = probe.waiting()
    first = probe.next_goal(status)
    ran = probe.send(first)
    if not ran.answers:
        raise _TimedOut(f"the first child did not end within {probe.timeout:g} s")
    child = ran.answers[0][1].id or first.id  # R8.1: the result names the child (D10: maybe not first.id)
    after = probe.link.wait_status(lambda s: s.id == child and machine.robot_waits(s), probe.timeout)
    if after is None:
        raise _TimedOut(f"no status after child {child} ended within {probe.timeout:g} s")
    probe.note(f"status {status_text(after)}: the client's only state")
    exchange = probe.send(probe.next_goal(after))  # seq and the fresh id from that status alone
    fresh = _fresh(after.id)
    return _ran_finding(probe, case, exchange, fresh, f"child {fresh} runs and completes")


def _race(probe: Probe, case: Case) -> CaseFinding:
    status = probe.waiting()
    goals = [probe.next_goal(status), probe.next_goal(status, goal_id=_within_ids(status.id + 2))]
    exchanges = [probe.link.send(goal) for goal in goals]  # at once: no wait between them
    probe.exchanges.extend(exchanges)
    for goal, exchange in zip(goals, exchanges, strict=True):
        exchange.responded(probe.timeout)
        if exchange.accepted:
            probe.answered(exchange)
        probe.note(f"{_describe_goal(goal)}: {_describe_answer(exchange)}, {len(exchange.feedback)} feedback")
    expected = (
        "one child runs and completes; the other NEXT rejected, or accepted and aborted without a child"
    )
    # what ran is the judge's to hold to the rules, on the case's records: two children (R5.2), a NEXT
    # that ran none answered other than aborted (R4.16, R5.2), a child numbered or answered wrong (R6.2)
    ran = [exchange for exchange in exchanges if exchange.feedback]
    if len(ran) != 1:
        count = f"{len(ran)} of the NEXTs ran a child"
        if not all(_complete(exchange) for exchange in exchanges):  # a response or feedback to come
            return _fails(case, "timeout", expected, count)
        if all(exchange.accepted is False for exchange in exchanges):  # what a configuration decides
            return _fails(case, "configuration", expected, count)
        return _seen_by_script(case, expected, count)
    seen = _ran(ran[0], ran[0].goal.id)
    if seen is not None and not _complete(ran[0]):
        return _fails(case, "timeout", expected, f"the child that ran: {seen}")
    other = exchanges[1] if ran[0] is exchanges[0] else exchanges[0]
    if other.accepted is None:
        return _fails(case, "timeout", expected, "the other NEXT: no response")
    # an unanswered other: R19.1, the judge's too
    return _seen_by_script(case, expected, f"the other NEXT: {_describe_answer(other)}")


def _log_seq(probe: Probe, case: Case) -> CaseFinding:
    children: list[list[LogEntry]] = []
    for _ in range(2):
        exchange = probe.send(probe.next_goal(probe.waiting()))
        if not exchange.answers:
            raise _TimedOut(f"a child did not end within {probe.timeout:g} s")
        children.append([entry for feedback in exchange.feedback for entry in feedback.logs])
    entries = [entry for logs in children for entry in logs]
    probe.note(f"log seqs of the two children: {[[entry.seq for entry in logs] for logs in children]}")
    expected = "each entry's seq one above the one before (modulo 2^32), across children; tiers " + ", ".join(
        tier.value for tier in Tier
    )
    if len(entries) < 2:
        return CaseFinding(
            case, Verdict.INFO, expected=expected, seen=f"{len(entries)} log entries: nothing to judge"
        )
    tiers = sorted({entry.tier for entry in entries} - {tier.value for tier in Tier})
    # R7.3 as the judge reads it: one up within a child, forward between children
    seqs = [(entry.seq, index > 0) for logs in children for index, entry in enumerate(logs)]
    pairs = itertools.pairwise(seqs)
    faults = {machine.log_seq_fault(last, seq, same_child=same) for (last, _), (seq, same) in pairs} - {""}
    gaps = [(b.seq - a.seq) % _U32 for a, b in itertools.pairwise(entries)]
    seen = f"tiers {tiers}; steps between entries {gaps}"
    if faults == {"skips"} and probe.link.apart:  # the judge seen apart: maybe feedback lost on the way
        return _fails(case, "log_seq", expected, seen)
    if tiers or faults:  # a tier none of the four (R7.2), a seq that repeats or goes back (R7.3): the judge's
        return _seen_by_script(case, expected, seen)
    return CaseFinding(case, Verdict.PASS, expected=expected, seen="so")


def _clamp_notice(probe: Probe, case: Case) -> CaseFinding:
    minimum = probe.options.stubborn_minimum
    if minimum <= 0:
        return CaseFinding(
            case, Verdict.INFO, expected="a clamp", seen="--stubborn-minimum 0: nothing to clamp"
        )
    goal = attrs.evolve(probe.next_goal(probe.waiting()), stubborn_period=minimum / 4)  # float32 on the wire
    period = goal.stubborn_period
    exchange = probe.send(goal)
    expected = (
        f"a warning log entry in the first feedback (stubborn period {period:g} s, minimum {minimum:g} s)"
    )
    if exchange.accepted is False:  # no child to warn of: whether the refusal was right is the judge's
        raise _Unreachable(f"the NEXT whose clamp the case looks for was {_describe_answer(exchange)}")
    if not exchange.feedback:
        return _fails(case, "timeout", expected, f"{_describe_answer(exchange)}, no feedback")
    warnings = [(i, entry) for i, feedback in enumerate(exchange.feedback) for entry in feedback.logs
                if entry.tier == Tier.WARNING.value]  # fmt: skip
    for index, entry in warnings:
        probe.note(f"feedback {index + 1}: warning {entry.text!r}")
    # a clamp not warned of in the start feedback (R12.2): the judge's, on the case's records
    if not warnings:
        return _seen_by_script(case, expected, "no warning: the clamp is silent")
    if warnings[0][0] != 0:
        return _seen_by_script(case, expected, f"the warning came with feedback {warnings[0][0] + 1}")
    return CaseFinding(case, Verdict.PASS, expected=expected, seen="so")


def _cancel_both_answered(probe: Probe, case: Case) -> CaseFinding:
    expected = "both CANCELs accepted and answered succeeded with the child's result; the NEXT answered once"
    with probe.child() as (running, child_id):
        status = probe.link.status or probe.any_status()
        cancels = [probe.link.send(_goal(status, EventType.CANCEL, id=child_id)) for _ in range(2)]
        probe.exchanges.extend(cancels)
        for cancel in cancels:
            cancel.responded(probe.timeout)
            cancel.answered(probe.timeout)
            probe.note(f"{_describe_goal(cancel.goal)}: {_describe_answer(cancel)}")
        running.answered(probe.timeout)
        probe.note(f"the NEXT: {_describe_answer(running)}")
        if not all(cancel.accepted for cancel in cancels):
            absent = any(cancel.accepted is None for cancel in cancels)
            if not probe.link.apart and not absent:  # records in the server's order: the judge's (R4.16)
                return _seen_by_script(case, expected, "a CANCEL not accepted")
            refused = [cancel for cancel in cancels if cancel.accepted is False]
            ended_by = [running, *(cancel for cancel in cancels if cancel.accepted)]
            late = all(_heard_after_end(probe, cancel, ended_by, child_id) for cancel in refused)
            if late and (
                any(_outlived(probe, cancel, child_id) for cancel in ended_by[1:])
                or all(_delayed(cancel, cancels) for cancel in refused)
                or len(refused) == len(cancels)  # none accepted: each may have come after the end
            ):
                why = REFUSED_AFTER_END.format(child=child_id)
                return CaseFinding(case, Verdict.MISSING, seen=why, by_link=True)
            return _fails(case, "timeout" if absent else "both_answered", expected, "a CANCEL not accepted")
        if running.answer is None or any(cancel.answer is None for cancel in cancels):
            return _fails(case, "timeout", expected, "a goal left without an answer")
        result = running.answer[1]
        wrong = [cancel for cancel in cancels if cancel.answer != (GoalStatus.SUCCEEDED, result)]
        if wrong:
            seen = f"a CANCEL {_describe_answer(wrong[0])}; the NEXT {_describe_answer(running)}"
            # the first CANCEL freed the robot before its child ended (D1), and the second, accepted,
            # was aborted as idle (in D8's words): when it started is not on the wire
            idle = [cancel for cancel in wrong if _aborted_with(cancel, Failure.IDLE_CANCEL)]
            if idle == wrong:
                return _fails(case, "start", expected, seen, divergence="D1")
            return _seen_by_script(case, expected, seen)  # answered otherwise: the judge's (R8.3)
        return CaseFinding(case, Verdict.PASS, expected=expected, seen="so")


def _heard_after_end(probe: Probe, refused: Exchange, ended_by: list[Exchange], child_id: int) -> bool:
    """Whether ``refused``'s refusal came after the probe had heard child ``child_id`` end: an answer
    to one of ``ended_by``, or a status without the child after one with it running.  Heard in that
    order, the refused goal may have reached the server after the end, where refusing it is right.  A
    refusal heard before every sign of the end is read as given while the child ran (a correct server
    sends the end's answers and status before any refusal that follows it: all of them would have had
    to come later than it)."""
    heard = refused.response_heard
    if heard is None:
        return False
    if any(other.answer_heard is not None and other.answer_heard < heard for other in ended_by):
        return True
    return _end_of(probe.link.history()[: refused.statuses_before_response], child_id) is not None


def _delayed(refused: Exchange, cancels: list[Exchange]) -> bool:
    """Whether ``refused``'s response came :data:`_RAN_ON` or more after that of a CANCEL sent with it
    and accepted: the two were sent at once, and a server takes them one after the other, so the link
    delayed the refused one's request (a lossy link sends a lost request again, late: it may have
    reached the server after the child's end) or its response."""
    came = [cancel.response_at for cancel in cancels if cancel.accepted and cancel.response_at is not None]
    return refused.response_at is not None and bool(came) and refused.response_at - min(came) >= _RAN_ON / 1e9


def _outlived(probe: Probe, cancel: Exchange, child_id: int) -> bool:
    """Whether child ``child_id`` ran on at the server for :data:`_RAN_ON` or more after it accepted
    ``cancel`` (by the server's stamps: its acceptance, and the status that shows the end), winding
    down as a child told to stop does: a goal sent with ``cancel`` may then have come after the end.
    A server that ends the child as it accepts the CANCEL (D1's defect) stamps the two together."""
    if cancel.accepted_at is None:
        return False
    probe.link.wait(lambda: _end_of(probe.link.history(), child_id) is not None, probe.timeout)
    history = probe.link.history()
    end = _end_of(history, child_id)
    return end is not None and _instant(history[end]) - cancel.accepted_at >= _RAN_ON


#: How long after a CANCEL's acceptance a child's end shows that it wound down (ns): a server that ends
#: it in the step that accepts the CANCEL stamps the two within a few milliseconds.
_RAN_ON = 50_000_000


def _end_of(history: list[DynamicEventStatus], child_id: int) -> int | None:
    """Where in ``history`` the first status comes that shows child ``child_id`` no longer running
    after one that showed it running; None where none has come."""
    running = [machine.runs_a_child(status) and status.id == child_id for status in history]
    if True not in running:
        return None
    return next((n for n in range(running.index(True), len(history)) if not running[n]), None)


def _aborted_with(exchange: Exchange, failure: Failure) -> bool:
    answer = exchange.answer
    return (
        answer is not None
        and answer[0] is GoalStatus.ABORTED
        and answer[1].execution_failure == failure.value
    )


def _action_cancel_running(probe: Probe, case: Case) -> CaseFinding:
    with probe.child() as (running, _):
        return _cancel_of_the_next(probe, case, running)


def _action_cancel_queued(probe: Probe, case: Case) -> CaseFinding:
    """The cancel goes as soon as the NEXT's acceptance is heard: over a link that hands an accepted
    goal over at its next turn (in process, the driver protocol) the NEXT waits to start, and R10.1
    answers it; over DDS, where a binding starts it with its acceptance, R10.3 does."""
    exchange = probe.send(probe.next_goal(probe.waiting()), answer=False)
    if not exchange.accepted:
        raise _Unreachable(f"the NEXT whose cancel the case sends was {_describe_answer(exchange)}")
    try:
        return _cancel_of_the_next(probe, case, exchange)
    finally:
        probe.stop_unanswered(exchange)


def _action_cancel_waiting(probe: Probe, case: Case) -> CaseFinding:
    """R10.2: a CANCEL of the running child waits for the child's end (R9.3); an action-level cancel of
    that CANCEL, sent once its acceptance is heard and the link's turn has passed (a link that hands an
    accepted goal over at its next turn starts it then), answers it ``cancelled while not running``,
    and the child's cancellation goes on: the NEXT is answered at the child's end, which the CANCEL
    brought early (R8.2: aborted, its result's status canceled, as for a CANCEL not cancelled)."""
    expected = (
        "the cancel accepted; the CANCEL answered canceled 'cancelled while not running'; the NEXT "
        "answered at its child's end, which the CANCEL brought early (R8.2: aborted, status canceled)"
    )
    with probe.child() as (running, child_id):
        status = probe.link.status or probe.any_status()
        stop = probe.send(_goal(status, EventType.CANCEL, id=child_id), answer=False)
        if not stop.accepted:
            raise _Unreachable(f"the CANCEL of the running child was {_describe_answer(stop)}")
        probe.link.turn()
        accepted = probe.cancel(stop)
        stop.answered(probe.timeout)
        running.answered(probe.timeout)
        probe.note(f"the CANCEL: {_describe_answer(stop)}; the NEXT: {_describe_answer(running)}")
        if stop.cancel_found_ended:  # refused rightly (R10.5): the child, and its CANCEL, had ended
            raise _Unreachable(CANCEL_ENDED)
        if accepted is None:
            return _no_cancel_response(probe, case, expected, stop)
        if stop.answer is None or running.answer is None:
            return _fails(case, "timeout", expected, "a goal left without an answer")
        seen = (
            f"the cancel {'accepted' if accepted else 'refused'}; the CANCEL {_describe_answer(stop)}; "
            f"the NEXT {_describe_answer(running)}"
        )
        answered = stop.answer[0] is GoalStatus.CANCELED and _failed_with(stop, Failure.NOT_RUNNING)
        if not (accepted and answered):  # the cancel or the CANCEL's answer (R10.1, R10.2): the judge's
            return _seen_by_script(case, expected, seen)
        if not machine.ends_early(running.answer[1].status):
            # the child's cancellation stopped: where records are in the server's order, the link's turn
            # started the CANCEL before the cancel came; at a client's tap that start is unknown, and the
            # judge reads the cancel as of a CANCEL not yet started (R10.1), which lets the child run on
            if probe.link.apart:
                return _seen_by_script(case, expected, seen)
            return _fails(case, "start", expected, seen)
        return CaseFinding(case, Verdict.PASS, expected=expected, seen="so")


def _run_command(probe: Probe, flag: str, command: str, *, succeed: bool = False) -> str:
    """Run ``command`` (bounded by the timeout, or :data:`COMMAND_BOUND` where that is longer), noting
    its exit status: ``""``, or why it did not run (with ``succeed``, or did not exit 0)."""
    try:
        done = subprocess.run(
            shlex.split(command),
            timeout=max(probe.timeout, COMMAND_BOUND),
            check=False,
            capture_output=True,
            text=True,
        )
    except (OSError, ValueError, subprocess.TimeoutExpired) as exc:
        return f"{flag} {command!r} did not run: {exc}"
    probe.note(f"ran {flag}: exit status {done.returncode}")
    if succeed and done.returncode != 0:
        said = done.stdout.strip().splitlines()[-1:] or done.stderr.strip().splitlines()[-1:]
        return f"{flag} {command!r} exited {done.returncode}" + (f": {said[0]}" if said else "")
    return ""


def _task_input(probe: Probe, what: str) -> str:
    """Interrupt or resume (``what``) the robot's task: by ``--interrupt-command`` or
    ``--resume-command`` when given, else through the link; ``""`` once done, else why not."""
    command = probe.options.interrupt_command if what == "interrupt" else probe.options.resume_command
    if command:
        return _run_command(probe, f"--{what}-command", command, succeed=True)
    return probe.link.interrupt() if what == "interrupt" else probe.link.resume()


@contextmanager
def _interrupted(probe: Probe) -> Iterator[None]:
    """The robot's task interrupted while the block runs (R14.2), then resumed (R14.3)."""
    why = _task_input(probe, "interrupt")
    if why:
        raise _Unreachable(why)
    probe.note("the task interrupted")
    try:
        yield
    finally:
        why = _task_input(probe, "resume")
        probe.note(f"the task not resumed: {why}" if why else "the task resumed")


def _deferred(probe: Probe, status: DynamicEventStatus) -> tuple[Exchange, Feedback | None]:
    """A NEXT sent while the task is interrupted, accepted, and its first feedback (None where none
    came within the timeout): R6.3's ``queued`` where the server defers its child's start."""
    exchange = probe.send(probe.next_goal(status), answer=False)
    if not exchange.accepted:
        raise _Unreachable(f"the NEXT sent while the task was interrupted was {_describe_answer(exchange)}")
    exchange.wait(lambda: bool(exchange.feedback or exchange.answers), probe.timeout)
    return exchange, exchange.feedback[0] if exchange.feedback else None


#: What a deferred start shows (R6.3).
_DEFERRED = "the NEXT's first feedback queued, its child's start deferred (R6.3)"


def _not_deferred(case: Case, first: Feedback | None) -> CaseFinding | None:
    """The case's failure where the NEXT sent while the task was interrupted was not deferred."""
    if first is None:
        return _fails(case, "timeout", _DEFERRED, "no feedback")
    if first.status != Status.QUEUED.value:
        return _fails(case, "interrupt", _DEFERRED, f"feedback {first.status!r} id {first.id}")
    return None


def _interrupt_deferred_start(probe: Probe, case: Case) -> CaseFinding:
    """R14.2, R6.3, R14.5: while the task is interrupted a NEXT's child waits (feedback ``queued``);
    the resume starts it."""
    expected = f"{_DEFERRED}; the resume starts it (its next feedback, R14.5)"
    with _interrupted(probe):
        exchange, first = _deferred(probe, probe.waiting())
    try:
        failed = _not_deferred(case, first)
        if failed is not None:
            return failed
        exchange.wait(lambda: len(exchange.feedback) > 1 or bool(exchange.answers), probe.timeout)
        if len(exchange.feedback) < 2:
            return _fails(case, "timeout", expected, "no feedback after the resume")
        after = exchange.feedback[1]
        return _seen_by_script(case, expected, f"feedback queued, then {after.status!r} after the resume")
    finally:
        probe.stop_unanswered(exchange)


def _interrupt_cancel_deferred(probe: Probe, case: Case) -> CaseFinding:
    """R9.4: a CANCEL of a child whose start the interruption deferred cancels it at once: the NEXT
    and the CANCEL answered, canceled, without a resume.  (A CANCEL refused, or answered otherwise, is
    the judge's.)"""
    expected = "the CANCEL of the deferred child and its NEXT answered at once, canceled (R9.4)"
    status = probe.waiting()
    made: list[Exchange] = []
    try:
        with _interrupted(probe):
            exchange, first = _deferred(probe, status)
            made.append(exchange)
            failed = _not_deferred(case, first)
            if failed is not None or first is None:
                return failed or _fails(case, "timeout", _DEFERRED, "no feedback")
            stop = probe.send(_goal(status, EventType.CANCEL, id=first.id))
            exchange.answered(probe.timeout)
            seen = f"the CANCEL {_describe_answer(stop)}; the NEXT {_describe_answer(exchange)}"
            if stop.accepted is None or (stop.accepted and (stop.answer is None or exchange.answer is None)):
                return _fails(case, "timeout", expected, seen)
            return _seen_by_script(case, expected, seen)
    finally:  # once the task is resumed: a child still deferred starts, and is stopped
        for exchange in made:
            probe.stop_unanswered(exchange)


def _interrupt_action_cancel_deferred(probe: Probe, case: Case) -> CaseFinding:
    """R10.4: an action-level cancel of a NEXT whose child's start the interruption deferred is
    accepted and answers it at once, canceled, without a resume."""
    expected = "the cancel accepted; the NEXT answered canceled at once (R10.4)"
    made: list[Exchange] = []
    try:
        with _interrupted(probe):
            exchange, first = _deferred(probe, probe.waiting())
            made.append(exchange)
            failed = _not_deferred(case, first)
            if failed is not None:
                return failed
            accepted = probe.cancel(exchange)
            exchange.answered(probe.timeout)
            if accepted is None:
                return _no_cancel_response(probe, case, expected, exchange)
            if accepted and exchange.answer is None:
                return _fails(case, "timeout", expected, "the NEXT not answered")
            seen = f"the cancel {'accepted' if accepted else 'refused'}; "
            return _seen_by_script(case, expected, seen + f"the NEXT {_describe_answer(exchange)}")
    finally:  # once the task is resumed
        for exchange in made:
            probe.stop_unanswered(exchange)


def _no_cancel_response(probe: Probe, case: Case, expected: str, exchange: Exchange) -> CaseFinding:
    """The case's failure where the action-level cancel of ``exchange``'s goal heard no response within
    the timeout; seen again at the run's end, a response that came since makes it not run, saying so
    (found at 10% loss across hosts: a cancel's response 12 s after its request)."""
    probe.heard_later[case.id] = lambda: exchange.cancel_heard
    return _fails(case, "timeout", expected, "no cancel response")


def _failed_with(exchange: Exchange, failure: Failure) -> bool:
    answer = exchange.answer
    return answer is not None and answer[1].execution_failure == failure.value


def _cancel_of_the_next(probe: Probe, case: Case, exchange: Exchange) -> CaseFinding:
    """An action-level cancel of the NEXT ``exchange``, accepted, and the NEXT answered canceled."""
    expected = "the cancel accepted; the NEXT answered canceled"
    accepted = probe.cancel(exchange)
    exchange.answered(probe.timeout)
    probe.note(f"the NEXT: {_describe_answer(exchange)}")
    if exchange.cancel_found_ended:  # refused rightly (R10.5): the cancel came after the child's end
        raise _Unreachable(CANCEL_AFTER_END)
    if accepted is None:
        return _no_cancel_response(probe, case, expected, exchange)
    if accepted and exchange.answer is None:
        return _fails(case, "timeout", expected, "the NEXT not answered")
    # the cancel refused (R10.1, R10.3), or the NEXT answered other than canceled (R8.2): the judge's
    if not accepted or (exchange.answer is not None and exchange.answer[0] is not GoalStatus.CANCELED):
        return _seen_by_script(case, expected, f"the cancel {'accepted' if accepted else 'refused'}; "
                               f"the NEXT {_describe_answer(exchange)}")  # fmt: skip
    return CaseFinding(case, Verdict.PASS, expected=expected, seen="so")


def _action_cancel_answered(probe: Probe, case: Case) -> CaseFinding:
    exchange = probe.send(probe.next_goal(probe.waiting()))
    if not exchange.answers:
        raise _TimedOut(f"the child did not end within {probe.timeout:g} s")
    accepted = probe.cancel(exchange)
    if accepted is None:
        return _no_cancel_response(probe, case, "the cancel refused", exchange)
    if accepted:  # the judge finds the cancel response the machine does not give (R10.5)
        return _seen_by_script(case, "the cancel refused", "the cancel accepted")
    return CaseFinding(case, Verdict.PASS, expected="the cancel refused", seen="so")


def _describe(probe: Probe) -> tuple[Any, str]:
    """The description query's answer, or None and why there is none (:meth:`Link.describe`); an
    answer tells :attr:`Link.query_answered` that the server offers the query."""
    answer, why = probe.link.describe(probe.timeout)
    probe.link.query_answered = probe.link.query_answered or answer is not None
    return answer, why


def _describe_query(probe: Probe, case: Case) -> CaseFinding:
    status = probe.waiting()
    return _query_answers(probe, case, status, status.status)


def _describe_after_child(probe: Probe, case: Case) -> CaseFinding:
    """R16.2 once a child has ended: the query names the run's current id, the child's (asked before
    any child, as describe.query is, the run's first id is the current one too).  The status it
    answers is describe.query's: a status published wrongly at a child's end (R8.4, the
    status's cases) would make a right answer differ from it."""
    child, after = _child_ended(probe, probe.waiting())
    if after is None:
        raise _TimedOut(f"no status after child {child} within {probe.timeout:g} s")
    probe.note(f"status {status_text(after)}")
    return _query_answers(probe, case, after, None)


def _query_answers(
    probe: Probe, case: Case, status: DynamicEventStatus, wanted_status: str | None
) -> CaseFinding:
    """R16.2: the query answers running, ``status``'s id (of the latest status the robot published),
    ``wanted_status`` (any where None) and the run's description (its begin's); ``info`` where the
    server offers no query."""
    answer, why = _describe(probe)
    if answer is None:
        probe.note(why)
        return CaseFinding(case, Verdict.INFO, expected="an answer, where the server offers the query",
                       seen=f"{why} (a server need not offer it: rmf_ros2 does not, D17)")  # fmt: skip
    begun = [begin for begin in probe.link.begins if begin.dynamic_event_seq == status.dynamic_event_seq]
    got = (bool(answer.running), str(answer.status), int(answer.id))
    wanted = (True, got[1] if wanted_status is None else wanted_status, status.id)
    probe.note(f"answer: running={got[0]} status={got[1]} id={got[2]} description={answer.description!r}")
    expected = f"running, {wanted_status or 'any status'}, id {status.id}, the begin's description"
    if got != wanted or (begun and answer.description != begun[-1].description):
        return _fails(
            case, "query", expected, f"running={got[0]}, {got[1]}, id {got[2]}, {answer.description!r}"
        )
    return CaseFinding(case, Verdict.PASS, expected=expected, seen="so")


def _describe_after(probe: Probe, case: Case) -> CaseFinding:
    """R16.1: asked between a run's end and the next run's begin (the case ends the run with a FINISHED
    where one is active), the query answers ``DescriptionResponse()``.  A server that gives no answer
    fails where it answered the query during a run (it offers the query), and is ``info`` otherwise."""
    status = probe.any_status()
    ended = [  # the runs the probe's FINISHEDs ended, by their answers
        made.goal.dynamic_event_seq for made in probe.link.made
        if made.goal.event_type == EventType.FINISHED.value and made.answer is not None
        and made.answer[0] is GoalStatus.SUCCEEDED
    ]  # fmt: skip
    if status.dynamic_state != DynamicState.INACTIVE and ended:
        if status.dynamic_event_seq != ended[-1]:
            raise _Unreachable(BEGAN_FIRST.format(later=status.dynamic_event_seq, ended=ended[-1], seen=""))
        probe.note(f"run {ended[-1]} ended (its FINISHED succeeded), though no INACTIVE status came")
    elif status.dynamic_state != DynamicState.INACTIVE:  # no run ended: the case ends this one
        _describe(probe)  # during the run: does the server offer the query?
        finishing = probe.send(_goal(status, EventType.FINISHED))
        if finishing.answer is None or finishing.answer[0] is not GoalStatus.SUCCEEDED:
            raise _Unreachable(f"the FINISHED that ends run {status.dynamic_event_seq} was "
                               f"{_describe_answer(finishing)}")  # fmt: skip
        inactive = probe.link.wait_status(lambda s: s.dynamic_state == DynamicState.INACTIVE, probe.timeout)
        if inactive is None:
            raise _TimedOut(f"no INACTIVE status within {probe.timeout:g} s after the FINISHED")
        status = inactive
    seq = status.dynamic_event_seq
    expected = "not running, every field empty (status '', description '', id 0)"
    answer, why = _describe(probe)
    if answer is None:
        probe.note(why)
        if not probe.link.query_answered:
            return CaseFinding(case, Verdict.INFO, expected="an answer, where the server offers the query",
                           seen=f"{why} (a server need not offer it: rmf_ros2 does not, D17)")  # fmt: skip
        return _fails(case, "timeout", expected, f"{why}, where it answered the query during a run")
    got = (bool(answer.running), str(answer.status), str(answer.description), int(answer.id))
    if got == (False, "", "", 0):
        return CaseFinding(case, Verdict.PASS, expected=expected, seen="so")
    seen = f"running={got[0]}, status {got[1]!r}, id {got[3]}, description {got[2]!r}"
    if got[0] and got[1] == _STANDBY:  # a run's first status: the next run may have begun before the query
        probe.link.wait(lambda: _run_after(probe.link, seq) is not None, probe.timeout)
        later = _run_after(probe.link, seq)
        if later is not None:
            why = BEGAN_FIRST.format(later=later, ended=seq, seen=f" ({seen})")
            return CaseFinding(case, Verdict.MISSING, seen=why, by_link=True)
    return _fails(case, "query", expected, seen)


def _run_after(link: Link, seq: int) -> int | None:
    """The seq of a run after run ``seq`` that the link has heard of, by its begin or a status (each
    topic read apart: found at 30% loss across hosts, the next run's begin heard and its status lost
    until after the case's wait); None where none."""
    seqs = [begin.dynamic_event_seq for begin in list(link.begins)]
    seqs += [status.dynamic_event_seq for status in link.history()]
    return next((later for later in seqs if seq_after(later, seq)), None)


_LAST_SEQ = U32_MAX


def _seq_wrap(probe: Probe, case: Case) -> CaseFinding:
    status = probe.waiting()
    if status.dynamic_event_seq == _LAST_SEQ:
        ended = probe.send(_goal(status, EventType.FINISHED))
        if not ended.answers:
            raise _Unreachable(f"the FINISHED that ends run {_LAST_SEQ} was {_describe_answer(ended)}")
        probe.link.wait_status(
            lambda s: s.dynamic_event_seq != _LAST_SEQ and machine.robot_waits(s), probe.timeout
        )
        status = probe.waiting()
    seqs = [s.dynamic_event_seq for s in probe.link.history() if s.dynamic_state != DynamicState.INACTIVE]
    if _LAST_SEQ not in seqs:
        raise _Unreachable(
            f"the wrap needs a run {_LAST_SEQ} (e.g. dynevent serve --first-seq {_LAST_SEQ}); this run is "
            f"{status.dynamic_event_seq}"
        )
    last = len(seqs) - 1 - seqs[::-1].index(_LAST_SEQ)
    after = [seq for seq in seqs[last:] if seq != _LAST_SEQ]
    if not after:
        raise _TimedOut(f"no run began after run {_LAST_SEQ} within {probe.timeout:g} s")
    begun = probe.link.wait_begin(after[0], probe.timeout)
    begins = sorted({begin.dynamic_event_seq for begin in probe.link.begins})
    probe.note(f"the run after {_LAST_SEQ}: {after[0]}; begins seen for runs {begins}")
    expected = f"run 0 after run {_LAST_SEQ}, begun on the begin topic; a goal for {_LAST_SEQ} refused"
    if not begun:  # the begin of the run after the wrap never came
        return _fails(
            case, "timeout", expected, f"run {after[0]}; begins for {begins} within {probe.timeout:g} s"
        )
    if after[0] != 0:  # the judge finds the run's seq the machine does not give (R3.1)
        return _seen_by_script(case, expected, f"run {after[0]}; begins for {begins}")
    if status.dynamic_event_seq != 0:
        raise _Unreachable(f"run 0 is over: the robot is in run {status.dynamic_event_seq}")
    finding = probe.refused(case, _goal(status, EventType.FINISHED, dynamic_event_seq=_LAST_SEQ))
    return attrs.evolve(finding, expected=expected)


_CASES: dict[str, Callable[[Probe, Case], CaseFinding]] = {
    "status.latched": _status_latched,
    "status.waiting": _status_waiting,
    "describe.query": _describe_query,
    "describe.after_child": _describe_after_child,
    "interrupt.deferred_start": _interrupt_deferred_start,
    "interrupt.cancel_deferred": _interrupt_cancel_deferred,
    "interrupt.action_cancel_deferred": _interrupt_action_cancel_deferred,
    "request.seq_stale": _seq_stale,
    "request.seq_future": _seq_future,
    "request.seq_stale_next": _seq_stale_next,
    "request.seq_future_next": _seq_future_next,
    "request.event_type_0": _event_type_0,
    "request.event_type_unknown": _event_type_unknown,
    "request.category_unknown": _category_unknown,
    "request.description_not_json": _description_not_json,
    "request.description_invalid": _description_invalid,
    "request.stubborn_nan": _stubborn_nan,
    "request.cancel_idle": _cancel_idle,
    "next.runs_a_child": _runs_a_child,
    "next.id_zero": _id_zero,
    "next.id_chosen": _id_chosen,
    "next.stateless_id": _stateless_id,
    "next.id_stale": _id_stale,
    "next.status_after_child": _status_after_child,
    "next.busy": _busy,
    "next.busy_finished": _busy_finished,
    "next.race": _race,
    "feedback.log_seq": _log_seq,
    "stubborn.clamp_notice": _clamp_notice,
    "cancel.wrong_id": _cancel_wrong_id,
    "cancel.seq_stale": _cancel_seq_stale,
    "cancel.seq_future": _cancel_seq_future,
    "cancel.running_child": _cancel_running_child,
    "cancel.both_answered": _cancel_both_answered,
    "action.cancel_running": _action_cancel_running,
    "action.cancel_queued": _action_cancel_queued,
    "action.cancel_waiting": _action_cancel_waiting,
    "action.cancel_answered": _action_cancel_answered,
    "finished.ends_the_run": _finished,
    "describe.after_the_run": _describe_after,
    "finished.next_after": _next_after,
    "finished.cancel_after": _cancel_after,
    "finished.finished_after": _finished_after,
    "begin.seq_wrap": _seq_wrap,
}


def implemented() -> frozenset[str]:
    """The ids of the cases this module carries out."""
    return frozenset(_CASES)


def runnable(
    cases: list[Case], link: type[Link] | Link, options: Options, say: Callable[[str], None]
) -> list[Case]:
    """The ``cases`` a link runs: those that interrupt the robot's task left out where neither the link
    (:attr:`Link.interrupts`) nor a command of ``options`` (``--interrupt-command``) can, saying so."""
    interrupts = link.interrupts or bool(options.interrupt_command)
    left_out = [case.id for case in cases if case.interrupts and not interrupts]
    if left_out:
        say(f"left out: {', '.join(left_out)} ({INTERRUPT_UNOFFERED})")
    return [case for case in cases if case.id not in left_out]


def run_cases(
    link: Link,
    options: Options,
    cases: list[Case],
    say: Callable[[str], None],
    progress: Callable[[str], None] | None = None,
    findings: list[CaseFinding] | None = None,
) -> list[CaseFinding]:
    """Carry out ``cases`` over ``link`` (its server found), appending each finding to ``findings``
    (a list the caller keeps, so that an interruption keeps those of the cases that ended); the
    findings."""
    findings = [] if findings is None else findings
    cases = runnable(cases, link, options, say)
    probe = Probe(link, options)  # the deadline runs from here: the first wait is within it too
    probe.options = _ready(link, options, cases, say, probe.timeout)
    if not link.statuses:  # _ready waited --timeout (or what the deadline left) for one
        offered = link.offered.get("status")
        cause = f": the status topic is {offered}" if offered is not None else " (R1.4)"
        probe.dead["status"] = f"no status was heard within {options.timeout:g} s{cause}"
    for case in cases:
        _hear_out_silence(probe)
        why = STOPPED_ANSWERING if probe.silent else probe.blocked(case)
        if why is not None:
            findings.append(probe.not_run(case, why))
            continue
        if progress is not None:
            progress(f"{case.id} ...")
        findings.append(probe.run(case))
    # what a case waited for in vain may still be on its way over a lossy link (the last cases' most
    # of all), and so may the response to a goal the last case sent: the run's end waits for them,
    # once, within --timeout and what the deadline leaves
    pending = [finding for finding in findings if finding.absent and finding.verdict is Verdict.FAIL]
    probe.abandoned.extend(
        made for made in link.made if made.accepted is None and made not in probe.abandoned
    )
    if not probe.past_deadline:
        link.wait(lambda: _heard_out(probe, pending), probe.timeout)
    findings[:] = [_fell_silent(probe, _late(probe, finding)) for finding in findings]
    lost = _losses(probe.link, findings)
    # what never came, log seqs that skip, a CANCEL refused before the end was heard: no verdict over
    # a link that lost messages
    if lost is not None:
        findings[:] = [_lossy(finding, lost) for finding in findings]
    elif not (probe.past_deadline or link.cut_off or _lagged(probe, findings)):
        link.end()  # heard out: the judge finds what the machine owed by now and never came (R19.1)
    return findings


def _lagged(probe: Probe, findings: list[CaseFinding]) -> bool:
    """Whether the run showed the link lagging or gone: a response that came after its case gave up on
    it, or a case not run for the link's sake (the server fell silent, a case's messages came late or
    were lost, an earlier case's goal came late)."""
    late = any(made.accepted is not None for made in probe.abandoned)
    return late or any(finding.by_link for finding in findings)


def _heard_out(probe: Probe, pending: list[CaseFinding]) -> bool:
    """Whether what the ``pending`` cases waited for in vain has come since, and every goal sent has
    had its response, accepted its answer, and every action-level cancel its response."""
    came = all(_came_late(probe, finding) for finding in pending)
    return came and all(
        made.accepted is not None
        and (not made.accepted or made.answers)
        and made.cancels_heard >= made.cancels_asked
        for made in probe.link.made
    )


def _hear_out_status(probe: Probe) -> None:
    """Where no status came in the first wait nor in status.latched's, and the status topic is not
    offered so that none can come, wait once more, within ``--timeout``, before the cases that
    need an active run are not run (found at 30% loss across hosts: a latched status that a
    slowly repairing link delivered 21 s late, a second after the latched case's wait)."""
    if probe.link.statuses or "status" in probe.link.offered:
        return
    if not probe.status_waited and not probe.past_deadline:
        probe.status_waited = True
        probe.link.wait(lambda: bool(probe.link.statuses), probe.timeout)


def _hear_out_silence(probe: Probe) -> None:
    """Where the server fell silent after it had sent the probe anything (responded to goal requests,
    or published a status), wait once more, within ``--timeout``, for anything from it: a lossy link
    that repairs slowly delivers what the silent cases asked for seconds after their waits (found at
    30% loss across hosts: three responses came 13 s after the third wait, and the rest of the run
    was not run; again when those were the run's first three goals, 33 s after the first, its status
    heard long before).  Heard, the server is answering and the cases go on; not heard, the rest are
    not run (:data:`STOPPED_ANSWERING`), unless the server answers its description query
    (:func:`_answers_aside`)."""
    if not probe.silent or not probe.heard_before_silence or probe.silence_waited or probe.past_deadline:
        return
    heard = probe.link.heard
    if probe.link.wait(lambda: probe.link.heard != heard, probe.timeout):
        probe.silent_cases = []
    elif _answers_aside(probe):
        if probe.answered_before_silence:  # a server that never responded to a goal is failed for it
            probe.held_back.extend(probe.silent_cases)
        probe.silent_cases = []
    else:
        probe.silence_waited = True  # waited out once: the server is taken as silent


def _answers_aside(probe: Probe) -> bool:
    """Over a network (:attr:`Link.channels_lag`), whether a server that offers the description query
    (R16, read-only) answers it now, on a channel of its own, where the action's responses fell
    silent: it is answering, and the silence is the action's channel held back behind a message
    the link lost and has not yet sent again (found at 30% loss across hosts: a response 40 s late,
    past the three cases' waits and the wait once more, and the run not run on).  Asked within
    ``--timeout`` and what the deadline leaves."""
    link = probe.link
    if not (link.channels_lag and link.query_answered) or probe.past_deadline:
        return False
    answer, _ = link.describe(max(min(probe.timeout, link.time_left()), 0.0))
    return answer is not None


def _late(probe: Probe, finding: CaseFinding) -> CaseFinding:
    """A failure for a goal's response or answer that did not come within ``--timeout``
    (``absent``), seen again at the run's end: when every goal the case left unanswered has had
    its response and, accepted, its answer since (or the log seqs show its feedback was sent,
    :func:`_feedback_lost`), the link was slow or lossy: the case is not run, saying so."""
    if not (finding.absent and finding.verdict is Verdict.FAIL):
        return finding
    lost = _feedback_lost_in(probe, finding)
    if lost is not None:
        why = FEEDBACK_LOST.format(first=lost[0], last=lost[-1])
    elif _came_late(probe, finding):
        why = LATE.format(timeout=probe.options.timeout)
    else:
        return finding
    return attrs.evolve(finding, verdict=Verdict.MISSING, seen=f"{why} ({finding.seen})", absent=False,
                        by_link=True)  # fmt: skip


def _came_late(probe: Probe, finding: CaseFinding) -> bool:
    """Whether what ``finding``'s case waited for in vain has come since: its goals' responses,
    answers and start feedback, or what else it waited for (:attr:`Probe.heard_later`)."""
    unanswered = probe.unanswered.get(finding.case.id, [])
    later = probe.heard_later.get(finding.case.id)
    return (bool(unanswered) and all(_complete(exchange) for exchange in unanswered)) or (
        later is not None and later()
    )


def _fell_silent(probe: Probe, finding: CaseFinding) -> CaseFinding:
    """A failure for what never came, of a case of the silence that made the probe take the server
    as having stopped answering (:attr:`Probe.silent`), whose goal request heard no response, where
    the server had responded to goal requests before: a server that responds to no request any more,
    mid-run, is not told from a link that has gone down, so the case is not run, saying why, like
    those after it.  So is one of a silence the server's description query showed the link's
    (:data:`HELD_BACK`), where the server had responded to goal requests before: its response held
    back on a channel that lost it.  A server that never
    responded, or a wait for a status or an answer that never came while requests were responded
    to, is failed for it."""
    silence = probe.silent and probe.answered_before_silence and finding.case.id in probe.silent_cases
    held = finding.case.id in probe.held_back and any(
        made.accepted is None for made in probe.unanswered.get(finding.case.id, [])
    )  # its response still never came
    if not ((silence or held) and finding.case.id in probe.unresponded):
        return finding
    if finding.verdict is not Verdict.FAIL or not finding.absent:
        return finding
    seen = f"{HELD_BACK if held else STOPPED_ANSWERING + ', from this case on'} ({finding.seen})"
    return attrs.evolve(finding, verdict=Verdict.MISSING, seen=seen, absent=False, by_link=True)


def _lossy(finding: CaseFinding, lost: str) -> CaseFinding:
    """``finding`` over a link that ``lost`` messages: a case failed for what never came, for log
    seqs that skip within a child, or for a CANCEL refused while the child ran (as the probe heard
    it), is not run, saying why."""
    lossy = {"log_seq": LOSSY_LOGS, "both_answered": LOSSY_REFUSAL}
    if finding.verdict is not Verdict.FAIL or not (finding.absent or finding.cause in lossy):
        return finding
    why = (LOSSY if finding.absent else lossy[finding.cause]).format(lost=lost)
    return attrs.evolve(
        finding, verdict=Verdict.MISSING, seen=f"{why} ({finding.seen})", absent=False, by_link=True
    )


def _losses(link: Link, findings: list[CaseFinding]) -> str | None:
    """What shows the link lost or delayed the server's messages during the run: statuses its writer
    numbered that never came, and cases whose messages came after ``--timeout``, were lost, or were
    held back while the server answered its description query."""
    seen = []
    if link.statuses_missed:
        seen.append(f"{link.statuses_missed} status(es) published and never delivered")
    prefixes = (LATE.split("{", 1)[0], FEEDBACK_LOST.split("{", 1)[0], HELD_BACK)
    late = sum(1 for finding in findings if finding.seen.startswith(prefixes))
    if late:
        seen.append(f"{late} case(s) whose messages came late or were lost")
    return "; ".join(seen) or None


def _ready(
    link: Link, options: Options, cases: list[Case], say: Callable[[str], None], timeout: float
) -> Options:
    """Say, before any case runs, what the run will lack: a status (R1.4: a late subscriber gets one at
    once, waited for ``timeout`` seconds), or a place for the cases that send the robot somewhere
    (taken, without ``--place``, from the go_to_place estimate of the run's description when it names
    one).  A begin topic offered so that the probe's reader cannot match it is said too."""
    if link.wait_status(lambda status: True, timeout) is None:
        offered = link.offered.get("status")
        why = (
            f"the status topic is {offered}"
            if offered is not None
            else "its status topic should hold the latest status for a late subscriber "
            "(transient-local, R1.4)"
        )
        say(f"no status from {options.fleet}/{options.robot} within {timeout:g} s: {why}")
    if "begin" in link.offered:
        say(f"the begin topic of {options.fleet}/{options.robot} is {link.offered['begin']}")
    if options.place is not None:
        return options
    placed = [case for case in cases if case.needs in ("child", "place")]
    for begin in reversed(link.begins):
        named = probe_cases.place_of_run(begin.description)
        if named is not None:
            say(
                f"place: {named} (the go_to_place estimate of run {begin.dynamic_event_seq}; "
                "--place chooses another)"
            )
            return attrs.evolve(options, place=named)
    if placed:
        say(f"no --place, and no run's description names one: the {len(placed)} case(s) that send the robot "
            "somewhere will not run")  # fmt: skip
    return options


#: How the command writes a report ``--junit`` or ``--report`` asks for: ``write(path, text, flag)``, as
#: :func:`dynevent.files.write_text` does (the probe produces the text; the command writes the file).
ReportWriter = Callable[[str, str, str], None]


def conclude(
    findings: list[CaseFinding],
    trace: str,
    options: Options,
    say: Callable[[str], None],
    write: ReportWriter,
) -> tuple[int, list[CaseFinding]]:
    """The end of a run: the judge over every record of the exchange (``trace``, the trace's text)
    fails the cases whose own records show a finding on their rules
    (:func:`~dynevent.conformance.probe.cases.judge_verdicts`), the findings and the judge's own
    section said, the JUnit and readable reports handed to ``write`` where asked; the exit status and
    the findings.  What ``write`` raises (a :class:`~dynevent.errors.FileError`) passes on."""
    findings, judged = probe_cases.judge_verdicts(trace, findings, options.known)
    say(probe_cases.format_findings(findings, judged).rstrip("\n"))
    server = f"{options.fleet}/{options.robot}"
    outputs: list[tuple[str, str | None, Callable[[], str]]] = [
        ("junit", options.junit, lambda: probe_cases.junit_xml(findings, server, judged)),
        ("report", options.report, lambda: probe_cases.report(
            findings, server, html_form=str(options.report).lower().endswith((".html", ".htm")),
            judged=judged,
        )),
    ]  # fmt: skip
    for flag, path, text in outputs:
        if path:
            write(path, text(), f"--{flag}")
    return probe_cases.exit_status(findings, judged), findings


def took(seconds: float, options: Options, *, simulated: float | None = None) -> str:
    """The run's last line: what it took in real time, from the server found to the last case's end,
    and its bound (with the simulated time it spanned, on a link that simulates it)."""
    bound = f"--deadline {options.deadline:g} s"
    return took_line(seconds, bound if simulated is None else f"{simulated:.1f} s simulated; {bound}")
