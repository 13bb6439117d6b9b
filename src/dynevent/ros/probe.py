"""``dynevent probe``: test a live Dynamic Event server over ROS 2 alone, case by case.

The probe is a client that may break the protocol on purpose: it sends raw
goals (a stale seq, event type 0, a CANCEL naming another event...) through
its own action client and watches the robot's status and begin topics, with
nothing of the server's process imported.  Each case of
:data:`dynevent.tools.probe_cases.CASES` ends in a
:class:`~dynevent.tools.probe_cases.Finding`; every wait is bounded by
``--timeout``.  Over ROS a refusal carries no reason (D6), so a case judges
what a client can see: accepted or rejected, the feedback, the answer, the
status that follows.
"""

from __future__ import annotations

import json
import os
import shlex
import subprocess
import sys
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import attrs
import rclpy
from action_msgs.msg import GoalStatus as RosGoalStatus
from rclpy.action import ActionClient
from rclpy.executors import SingleThreadedExecutor

from dynevent.errors import InvalidMessage, ProbeError
from dynevent.ros import convert
from dynevent.ros.convert import DynamicEvent, RosDescription, RosStatus
from dynevent.ros.server import latched
from dynevent.ros.spinning import Spinner, bounded_close, close_down
from dynevent.tools import probe_cases
from dynevent.tools.check.trace import TraceWriter, observation
from dynevent.tools.probe_cases import Case, Finding, Verdict
from dynevent.wire.messages import DynamicEventDescription, DynamicEventStatus, Feedback, Goal, Result
from dynevent.wire.names import (
    ROBOT_BEGIN_TOPIC_DEPTH,
    STATUS_TOPIC_DEPTH,
    action_name,
    begin_topic,
    status_topic,
)
from dynevent.wire.vocab import ENDED_CHILD_STATUSES, DynamicState, EventType, GoalStatus

__all__ = ["Exchange", "Link", "Options", "Probe", "main", "run"]

_TERMINAL = {
    RosGoalStatus.STATUS_SUCCEEDED: GoalStatus.SUCCEEDED,
    RosGoalStatus.STATUS_CANCELED: GoalStatus.CANCELED,
    RosGoalStatus.STATUS_ABORTED: GoalStatus.ABORTED,
}
_U32 = 2**32


class Exchange:
    """One raw goal: whether it was accepted, its feedback, and its answer, each as it arrives."""

    def __init__(self, goal: Goal) -> None:
        self.goal = goal
        self.uuid = os.urandom(16).hex()
        self.accepted: bool | None = None
        self.feedback: list[Feedback] = []
        self.answers: list[tuple[GoalStatus, Result]] = []
        self._changed = threading.Condition()

    def _note(self, update: Callable[[], None]) -> None:
        with self._changed:
            update()
            self._changed.notify_all()

    def wait(self, condition: Callable[[], bool], timeout: float) -> bool:
        """Wait, at most ``timeout`` seconds, until ``condition()`` holds."""
        with self._changed:
            return self._changed.wait_for(condition, timeout)

    def responded(self, timeout: float) -> bool:
        return self.wait(lambda: self.accepted is not None, timeout)

    def answered(self, timeout: float) -> bool:
        return self.wait(lambda: bool(self.answers) or self.accepted is False, timeout)

    @property
    def answer(self) -> tuple[GoalStatus, Result] | None:
        return self.answers[0] if self.answers else None


class Link:
    """Raw access to one robot: its status and begin topics, and an action client without a client
    machine, so that the probe can send what a well-behaved client never would."""

    def __init__(self, node: Any, fleet: str, robot: str, trace: TraceWriter | None = None) -> None:
        self._node = node
        self.fleet, self.robot = fleet, robot
        self._trace = trace
        self.statuses: list[DynamicEventStatus] = []
        self.begins: list[DynamicEventDescription] = []
        self._changed = threading.Condition()
        self._status = node.create_subscription(
            RosStatus, status_topic(fleet, robot), self._on_status, latched(STATUS_TOPIC_DEPTH)
        )
        self._begin = node.create_subscription(
            RosDescription, begin_topic(fleet, robot), self._on_begin, latched(ROBOT_BEGIN_TOPIC_DEPTH)
        )
        self._action = ActionClient(node, DynamicEvent, action_name(fleet, robot))

    def _on_status(self, message: Any) -> None:
        try:
            status = convert.status_from_ros(message)
        except InvalidMessage:
            return
        self._record("status", message=status)
        with self._changed:
            self.statuses.append(status)
            self._changed.notify_all()

    def _on_begin(self, message: Any) -> None:
        try:
            begin = convert.begin_from_ros(message)
        except InvalidMessage:
            return
        self._record("begin", message=begin)
        with self._changed:
            self.begins.append(begin)
            self._changed.notify_all()

    def mark(self, text: str) -> None:
        """A comment in the trace: what the records after it belong to."""
        if self._trace is not None:
            self._trace.comment(text)

    def _record(self, kind: str, **fields: Any) -> None:
        if self._trace is not None:
            self._trace.write(observation(kind, time.time_ns(), **fields))

    def wait_for_server(self, timeout: float) -> bool:
        return bool(self._action.wait_for_server(timeout_sec=timeout))

    @property
    def status(self) -> DynamicEventStatus | None:
        with self._changed:
            return self.statuses[-1] if self.statuses else None

    def wait_status(
        self, condition: Callable[[DynamicEventStatus], bool], timeout: float
    ) -> DynamicEventStatus | None:
        """The latest status once it satisfies ``condition``, or None after ``timeout`` seconds."""

        def holds() -> bool:
            return bool(self.statuses) and condition(self.statuses[-1])

        with self._changed:
            return self.statuses[-1] if self._changed.wait_for(holds, timeout) else None

    def late_subscriber_hears(self, timeout: float) -> bool:
        """Whether a subscription made now receives a status (what transient-local keeps)."""
        heard = threading.Event()
        subscription = self._node.create_subscription(
            RosStatus,
            status_topic(self.fleet, self.robot),
            lambda _: heard.set(),
            latched(STATUS_TOPIC_DEPTH),
        )
        try:
            return heard.wait(timeout)
        finally:
            self._node.destroy_subscription(subscription)

    def send(self, goal: Goal) -> Exchange:
        exchange = Exchange(goal)
        self._record("goal", goal_uuid=exchange.uuid, message=goal)
        future = self._action.send_goal_async(
            convert.goal_to_ros(goal),
            feedback_callback=lambda message: self._on_feedback(exchange, message),
            goal_uuid=convert.uuid_to_ros(exchange.uuid),
        )
        future.add_done_callback(lambda done: self._on_response(exchange, done))
        return exchange

    def _on_response(self, exchange: Exchange, future: Any) -> None:
        handle = future.result()
        accepted = bool(handle is not None and handle.accepted)
        self._record("goal_response", goal_uuid=exchange.uuid, accepted=accepted)
        exchange._note(lambda: setattr(exchange, "accepted", accepted))
        if accepted:
            handle.get_result_async().add_done_callback(lambda done: self._on_result(exchange, done))

    def _on_result(self, exchange: Exchange, future: Any) -> None:
        response = future.result()
        status = _TERMINAL.get(response.status, GoalStatus.ABORTED)
        result = convert.result_from_ros(response.result)
        self._record("result", goal_uuid=exchange.uuid, status=status, message=result)
        exchange._note(lambda: exchange.answers.append((status, result)))

    def _on_feedback(self, exchange: Exchange, message: Any) -> None:
        try:
            feedback = convert.feedback_from_ros(message.feedback)
        except InvalidMessage:
            return
        self._record("feedback", goal_uuid=exchange.uuid, message=feedback)
        exchange._note(lambda: exchange.feedback.append(feedback))

    def destroy(self) -> None:
        self._action.destroy()


@attrs.frozen
class Options:
    """What the probe is pointed at and how long it waits."""

    fleet: str
    robot: str
    place: str | None = None
    category: str = "go_to_place"
    timeout: float = 10.0
    begin_command: str | None = None
    known: frozenset[str] = frozenset()
    trace: str | None = None


def _waits(status: DynamicEventStatus) -> bool:
    """Whether a status says the robot waits for a NEXT in an active run (R20.2)."""
    if status.dynamic_state == DynamicState.WAITING:
        return True
    return status.dynamic_state == DynamicState.RUNNING and status.status in ENDED_CHILD_STATUSES


class _Unreachable(Exception):
    """A case cannot be carried out: its finding is ``missing``."""


def _describe_goal(goal: Goal) -> str:
    kind = {0: "type 0", 1: "NEXT", 2: "CANCEL", 3: "FINISHED"}.get(
        goal.event_type, f"type {goal.event_type}"
    )
    detail = f" {goal.category} {goal.description}" if goal.event_type == EventType.NEXT else ""
    return f"sent {kind} seq={goal.dynamic_event_seq} id={goal.id}{detail}"


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

    # ---------------------------------------------------------------- carrying out

    def run(self, case: Case) -> Finding:
        self.messages = []
        self.exchanges = []
        self.link.mark(f"case {case.id}")
        started = time.monotonic()
        try:
            finding = _CASES[case.id](self, case)
        except _Unreachable as exc:
            finding = Finding(case, Verdict.MISSING, seen=str(exc))
        finding = self._answered_once(finding)
        finding = attrs.evolve(
            finding,
            messages=tuple(self.messages),
            seconds=time.monotonic() - started,
            known=finding.verdict is Verdict.FAIL and finding.divergence in self.options.known,
        )
        return finding

    def note(self, text: str) -> None:
        self.messages.append(text)

    def _answered_once(self, finding: Finding) -> Finding:
        """Every goal the case saw accepted, its own and its clean-up's, answered exactly once (R19.1):
        a case that otherwise passed fails when one was not."""
        for exchange in self.exchanges:
            goal = _describe_goal(exchange.goal).removeprefix("sent ")
            if exchange.accepted and not exchange.answered(self.options.timeout):
                what = f"{goal} accepted, no answer"
            elif len(exchange.answers) > 1:
                what = f"{goal} answered {len(exchange.answers)} times"
            else:
                continue
            self.note(f"{what} within {self.options.timeout:g} s (R19.1)")
            if finding.verdict in (Verdict.PASS, Verdict.NON_STRICT, Verdict.INFO):
                return Finding(
                    finding.case, Verdict.FAIL, expected="every accepted goal answered exactly once (R19.1)",
                    seen=what, absent="no answer" in what,
                )  # fmt: skip
        return finding

    def waiting(self) -> DynamicEventStatus:
        """The status of an active run the robot waits in, after the begin command when one is given
        and the robot is not waiting; else the case is missing.  Waiting is WAITING, or RUNNING with
        a child's final status (R20.2: what rmf_ros2 keeps publishing after a child ends)."""
        timeout = self.options.timeout
        status = self.link.wait_status(_waits, 0.5)
        if status is None and self.options.begin_command:
            self._run_begin_command()
        status = status or self.link.wait_status(_waits, timeout)
        if status is None:
            raise _Unreachable(f"no active run (a WAITING status) within {timeout:g} s")
        return status

    def _run_begin_command(self) -> None:
        """Run ``--begin-command`` (bounded by the timeout); a command that cannot run makes the case
        missing, with why."""
        command = self.options.begin_command or ""
        try:
            done = subprocess.run(
                shlex.split(command),
                timeout=self.options.timeout,
                check=False,
                capture_output=True,
                text=True,
            )
        except (OSError, ValueError, subprocess.TimeoutExpired) as exc:
            raise _Unreachable(f"--begin-command {command!r} did not run: {exc}") from None
        self.note(f"ran --begin-command: exit status {done.returncode}")

    def any_status(self) -> DynamicEventStatus:
        status = self.link.wait_status(lambda s: True, self.options.timeout)
        if status is None:
            raise _Unreachable(f"no status within {self.options.timeout:g} s")
        return status

    def send(self, goal: Goal, *, answer: bool = True) -> Exchange:
        """Send ``goal``; wait for the response and, when accepted and ``answer``, for its answer."""
        exchange = self.link.send(goal)
        self.exchanges.append(exchange)
        self.note(_describe_goal(goal))
        if not exchange.responded(self.options.timeout):
            self.note("no response")
            return exchange
        if answer and exchange.accepted:
            exchange.answered(self.options.timeout)
        self.note(_describe_answer(exchange))
        return exchange

    def next_goal(self, status: DynamicEventStatus, goal_id: int | None = None) -> Goal:
        if self.options.place is None:
            raise _Unreachable("no place to send the robot to: give --place")
        return Goal(
            dynamic_event_seq=status.dynamic_event_seq,
            event_type=EventType.NEXT,
            category=self.options.category,
            description=json.dumps({"one_of": [self.options.place]}),
            id=status.id + 1 if goal_id is None else goal_id,
        )

    def refused(self, case: Case, goal: Goal, divergence: str | None = None) -> Finding:
        """A case whose goal the spec refuses: pass when rejected.  Accepted and then aborted is the
        way ``divergence`` breaks it, when given."""
        exchange = self.send(goal)
        if exchange.accepted is False:
            return Finding(case, Verdict.PASS, expected="rejected", seen="rejected")
        if exchange.accepted is None:
            return Finding(case, Verdict.FAIL, expected="rejected", seen="no response", absent=True)
        answer = exchange.answer
        aborted = answer is not None and answer[0] is GoalStatus.ABORTED
        return Finding(
            case, Verdict.FAIL, expected="rejected", seen=_describe_answer(exchange),
            divergence=divergence if aborted else None,
        )  # fmt: skip

    @contextmanager
    def child(self) -> Iterator[tuple[Exchange, int]]:
        """A running child (its NEXT accepted and the status RUNNING with its id); cancelled after."""
        status = self.waiting()
        goal = self.next_goal(status)
        exchange = self.send(goal, answer=False)
        if not exchange.accepted:
            raise _Unreachable(f"the NEXT that should run a child was {_describe_answer(exchange)}")
        running = self.link.wait_status(
            lambda s: s.dynamic_state == DynamicState.RUNNING and s.id == goal.id, self.options.timeout
        )
        if running is None:
            raise _Unreachable(f"the child {goal.id} never showed RUNNING within {self.options.timeout:g} s")
        try:
            yield exchange, goal.id
        finally:
            if not exchange.answers:
                stop = Goal(dynamic_event_seq=goal.dynamic_event_seq, event_type=EventType.CANCEL, id=goal.id)
                self.send(stop)
                exchange.answered(self.options.timeout)
            self.link.wait_status(
                lambda s: _waits(s) or s.dynamic_state == DynamicState.INACTIVE, self.options.timeout
            )


# -------------------------------------------------------------------- the cases


def _status_latched(probe: Probe, case: Case) -> Finding:
    probe.any_status()
    if probe.link.late_subscriber_hears(probe.options.timeout):
        return Finding(case, Verdict.PASS, expected="a status", seen="a status")
    return Finding(case, Verdict.FAIL, expected="a late subscriber receives the status", seen="nothing")


def _status_waiting(probe: Probe, case: Case) -> Finding:
    status = probe.waiting()
    seq = status.dynamic_event_seq
    begins = [begin.dynamic_event_seq for begin in probe.link.begins]
    probe.note(f"status WAITING seq={seq} id={status.id} {status.status}; begins seen for runs {begins}")
    if status.status != "standby":
        return Finding(case, Verdict.FAIL, expected="WAITING, standby", seen=f"WAITING, {status.status}")
    if seq not in begins:
        return Finding(case, Verdict.FAIL, expected=f"a begin for run {seq}", seen=f"begins for {begins}")
    return Finding(case, Verdict.PASS, expected="WAITING, standby, begun", seen="so")


def _goal(status: DynamicEventStatus, event_type: int, **values: Any) -> Goal:
    fields: dict[str, Any] = {
        "dynamic_event_seq": status.dynamic_event_seq,
        "event_type": event_type,
        "id": 0,
    }
    fields.update(values)
    return Goal(**fields)


def _seq_stale(probe: Probe, case: Case) -> Finding:
    status = probe.waiting()
    goal = _goal(status, EventType.FINISHED, dynamic_event_seq=(status.dynamic_event_seq - 1) % _U32)
    return probe.refused(case, goal)


def _seq_future(probe: Probe, case: Case) -> Finding:
    status = probe.waiting()
    goal = _goal(status, EventType.FINISHED, dynamic_event_seq=(status.dynamic_event_seq + 1) % _U32)
    return probe.refused(case, goal)


def _event_type_0(probe: Probe, case: Case) -> Finding:
    return probe.refused(case, _goal(probe.waiting(), 0), divergence="D7")


def _event_type_unknown(probe: Probe, case: Case) -> Finding:
    return probe.refused(case, _goal(probe.waiting(), 4), divergence="D7")


def _category_unknown(probe: Probe, case: Case) -> Finding:
    status = probe.waiting()
    goal = _goal(status, EventType.NEXT, category="dynevent_probe_no_such_category", description="{}",
                 id=status.id + 1)  # fmt: skip
    return probe.refused(case, goal)


def _description_not_json(probe: Probe, case: Case) -> Finding:
    status = probe.waiting()
    goal = _goal(status, EventType.NEXT, category=probe.options.category, description="{not json",
                 id=status.id + 1)  # fmt: skip
    return probe.refused(case, goal)


def _cancel_idle(probe: Probe, case: Case) -> Finding:
    status = probe.waiting()
    return probe.refused(case, _goal(status, EventType.CANCEL, id=status.id), divergence="D8")


def _runs_a_child(probe: Probe, case: Case) -> Finding:
    status = probe.waiting()
    goal = probe.next_goal(status)
    exchange = probe.send(goal)
    expected = f"accepted; feedback for id {goal.id}; succeeded, completed, id {goal.id}"
    if not exchange.accepted:
        return Finding(case, Verdict.FAIL, expected=expected, seen=_describe_answer(exchange))
    ids = sorted({feedback.id for feedback in exchange.feedback})
    probe.note(f"feedback: {len(exchange.feedback)} message(s), ids {ids}")
    answer = exchange.answer
    if answer is None:
        return Finding(
            case,
            Verdict.FAIL,
            expected=expected,
            seen=f"no answer within {probe.options.timeout:g} s",
            absent=True,
        )
    status_, result = answer
    if ids != [goal.id] or (status_, result.status, result.id) != (
        GoalStatus.SUCCEEDED,
        "completed",
        goal.id,
    ):
        return Finding(
            case, Verdict.FAIL, expected=expected, seen=f"feedback ids {ids}; {_describe_answer(exchange)}"
        )
    return Finding(case, Verdict.PASS, expected=expected, seen="so")


def _id_stale(probe: Probe, case: Case) -> Finding:
    status = probe.waiting()
    goal = probe.next_goal(status, goal_id=status.id)  # not above the run's highest id
    if status.id == 0:
        raise _Unreachable("the run's highest id is 0: no stale id exists")
    finding = probe.refused(case, goal)
    if finding.verdict is Verdict.FAIL and "succeeded" in finding.seen:
        finding = attrs.evolve(finding, divergence="D10")  # the id was ignored and the child ran
    return finding


def _status_after_child(probe: Probe, case: Case) -> Finding:
    status = probe.waiting()
    goal = probe.next_goal(status)
    exchange = probe.send(goal)
    if not exchange.answers:
        raise _Unreachable(f"the child did not end within {probe.options.timeout:g} s")
    after = probe.link.wait_status(
        lambda s: s.id == goal.id and s.status != "underway", probe.options.timeout
    )
    if after is None:
        return Finding(
            case,
            Verdict.FAIL,
            expected=f"WAITING, id {goal.id}",
            seen="no status after the child",
            absent=True,
        )
    phase = DynamicState(after.dynamic_state).name
    probe.note(f"status {phase} seq={after.dynamic_event_seq} id={after.id} {after.status}")
    if after.dynamic_state == DynamicState.WAITING and after.status == "standby":
        return Finding(case, Verdict.PASS, expected=f"WAITING, standby, id {goal.id}", seen="so")
    divergence = "D2" if after.dynamic_state == DynamicState.RUNNING else None
    return Finding(case, Verdict.FAIL, expected=f"WAITING, standby, id {goal.id}",
                   seen=f"{phase}, {after.status}, id {after.id}", divergence=divergence)  # fmt: skip


def _busy(probe: Probe, case: Case) -> Finding:
    with probe.child() as (_, child_id):
        status = probe.link.status or probe.any_status()
        return probe.refused(case, probe.next_goal(status, goal_id=child_id + 1))


def _cancel_wrong_id(probe: Probe, case: Case) -> Finding:
    with probe.child() as (_, child_id):
        status = probe.link.status or probe.any_status()
        return probe.refused(case, _goal(status, EventType.CANCEL, id=child_id + 1000), divergence="D8")


def _cancel_running_child(probe: Probe, case: Case) -> Finding:
    expected = "CANCEL succeeded; the NEXT answered once, its child canceled"
    with probe.child() as (running, child_id):
        status = probe.link.status or probe.any_status()
        cancel = probe.send(_goal(status, EventType.CANCEL, id=child_id))
        running.answered(probe.options.timeout)
        probe.note(f"the NEXT: {_describe_answer(running)}")
        cancel_answer, next_answer = cancel.answer, running.answer
        if cancel_answer is None or next_answer is None:
            return Finding(
                case, Verdict.FAIL, expected=expected, seen="a goal left without an answer", absent=True
            )
        if len(running.answers) != 1 or len(cancel.answers) != 1:
            return Finding(case, Verdict.FAIL, expected=expected, seen="a goal answered twice")
        if cancel_answer[0] is not GoalStatus.SUCCEEDED or next_answer[1].status != "canceled":
            seen = f"CANCEL {_describe_answer(cancel)}; NEXT {_describe_answer(running)}"
            return Finding(case, Verdict.FAIL, expected=expected, seen=seen)
        return Finding(case, Verdict.PASS, expected=expected, seen="so")


def _finished(probe: Probe, case: Case) -> Finding:
    status = probe.waiting()
    exchange = probe.send(_goal(status, EventType.FINISHED))
    expected = "succeeded, completed; then INACTIVE"
    answer = exchange.answer
    if answer is None or (answer[0], answer[1].status) != (GoalStatus.SUCCEEDED, "completed"):
        return Finding(case, Verdict.FAIL, expected=expected, seen=_describe_answer(exchange))
    seq = status.dynamic_event_seq
    ended = probe.link.wait_status(
        lambda s: s.dynamic_state == DynamicState.INACTIVE or s.dynamic_event_seq != seq,
        probe.options.timeout,
    )
    if ended is None or (ended.dynamic_state != DynamicState.INACTIVE and ended.dynamic_event_seq == seq):
        return Finding(
            case, Verdict.FAIL, expected=expected, seen="the run's status did not end", absent=True
        )
    return Finding(case, Verdict.PASS, expected=expected, seen="so")


def _next_after(probe: Probe, case: Case) -> Finding:
    status = probe.any_status()
    if status.dynamic_state != DynamicState.INACTIVE:
        ended = [s for s in probe.link.statuses if s.dynamic_state == DynamicState.INACTIVE]
        if not ended:
            raise _Unreachable("no run has ended (no INACTIVE status seen)")
        status = ended[-1]
    goal = Goal(dynamic_event_seq=status.dynamic_event_seq, event_type=EventType.NEXT,
                category=probe.options.category, description="{}", id=status.id + 1)  # fmt: skip
    return probe.refused(case, goal)


_CASES: dict[str, Callable[[Probe, Case], Finding]] = {
    "status.latched": _status_latched,
    "status.waiting": _status_waiting,
    "request.seq_stale": _seq_stale,
    "request.seq_future": _seq_future,
    "request.event_type_0": _event_type_0,
    "request.event_type_unknown": _event_type_unknown,
    "request.category_unknown": _category_unknown,
    "request.description_not_json": _description_not_json,
    "request.cancel_idle": _cancel_idle,
    "next.runs_a_child": _runs_a_child,
    "next.id_stale": _id_stale,
    "next.status_after_child": _status_after_child,
    "next.busy": _busy,
    "cancel.wrong_id": _cancel_wrong_id,
    "cancel.running_child": _cancel_running_child,
    "finished.ends_the_run": _finished,
    "finished.next_after": _next_after,
}


def implemented() -> frozenset[str]:
    """The ids of the cases this module carries out."""
    return frozenset(_CASES)


def main(args: Any, cases: list[Case], say: Callable[[str], None]) -> int:
    """``dynevent probe``: run the cases, print the findings, write ``--junit``; the exit status."""
    options = Options(
        fleet=args.fleet, robot=args.robot, place=args.place, category=args.category, timeout=args.timeout,
        begin_command=args.begin_command, known=probe_cases.KNOWN.get(args.known or "", frozenset()),
        trace=args.trace,
    )  # fmt: skip
    live = sys.stdout.isatty()

    def progress(text: str) -> None:
        if live:
            sys.stdout.write(f"\r\033[K{text}")
            sys.stdout.flush()

    findings = run(cases, options, say, progress)
    if live:
        sys.stdout.write("\r\033[K")
    if findings is None:
        return 2
    say(probe_cases.format_findings(findings).rstrip("\n"))
    server = f"{options.fleet}/{options.robot}"
    outputs: dict[str, Callable[[], str]] = {
        "junit": lambda: probe_cases.junit_xml(findings, server),
        "report": lambda: probe_cases.report(
            findings, server, html_form=str(args.report).lower().endswith((".html", ".htm"))
        ),
    }
    for flag, text in outputs.items():
        path = getattr(args, flag)
        if path:
            try:
                Path(path).write_text(text(), "utf-8")
            except OSError as exc:
                raise ProbeError(f"--{flag} {path}: cannot write: {exc.strerror or exc}") from None
    return probe_cases.exit_status(findings)


def run(
    cases: list[Case],
    options: Options,
    say: Callable[[str], None],
    progress: Callable[[str], None] | None = None,
) -> list[Finding] | None:
    """Carry out ``cases`` against the robot; the findings, or None when no server was found."""
    trace = _open_trace(options)
    rclpy.init()
    node = rclpy.create_node("dynevent_probe")
    link = Link(node, options.fleet, options.robot, trace)
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    spinner = Spinner(executor, "dynevent-probe")
    spinner.start()
    try:
        if not link.wait_for_server(options.timeout):
            say(f"no Dynamic Event server for {options.fleet}/{options.robot} within {options.timeout:g} s")
            return None
        probe = Probe(link, options)
        findings = []
        for case in cases:
            if progress is not None:
                progress(f"{case.id} ...")
            findings.append(probe.run(case))
        return findings
    finally:
        with bounded_close():
            spinner.stop()
            link.destroy()
            close_down([node])
        if trace is not None:
            trace.close()


def _open_trace(options: Options) -> TraceWriter | None:
    if options.trace is None:
        return None
    try:
        return TraceWriter(options.trace, fleet=options.fleet, robot=options.robot)
    except OSError as exc:
        raise ProbeError(f"--trace {options.trace}: cannot write: {exc.strerror or exc}") from None
