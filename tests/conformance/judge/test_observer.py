"""``dynevent check``: observer mode over traces; a clean trace, one trace per violation, rmf_ros2's trace."""

from __future__ import annotations

import contextlib
import random
import re
from pathlib import Path
from typing import Any

import attrs
import pytest
from hypothesis import given
from hypothesis import strategies as st

from dynevent.conformance.judge import Report, TraceError, check_trace, divergences, read_trace, step_records
from dynevent.conformance.judge.observer import CLIENT_LOOKAHEAD
from dynevent.conformance.judge.trace import TAPS, TraceWriter
from dynevent.server import inputs as ins
from dynevent.server import machine
from dynevent.wire import _json
from dynevent.wire.messages import Goal

ROOT = Path(__file__).resolve().parents[3]
EXAMPLES = ROOT / "docs" / "examples"
CONFIG = {
    "type": "config",
    "fleet": "tinyRobot",
    "robot": "tinyRobot1",
    "config": {"categories": {"go_to_place": {"accept": "any"}}},
}


def uuid(n: int) -> str:
    return f"{n:032x}"


class Trace:
    """A trace written record by record; times advance by 0.1 s per call."""

    def __init__(self, config: bool = True) -> None:
        self.rows: list[dict[str, Any]] = [CONFIG] if config else []
        self.time = 100.0

    def add(self, kind: str, **fields: Any) -> Trace:
        self.time = round(self.time + 0.1, 1)
        self.rows.append({"time": self.time, "type": kind, **fields})
        return self

    def begin(self, seq: int = 1) -> Trace:
        message = {"fleet": "tinyRobot", "robot": "tinyRobot1", "dynamic_event_seq": seq, "description": "{}"}
        return self.add("begin", message=message)

    def status(self, seq: int, phase: int, status: str, event_id: int) -> Trace:
        message = {"dynamic_event_seq": seq, "dynamic_state": phase, "status": status, "id": event_id}
        return self.add("status", message=message)

    def goal(self, n: int, accepted: bool = True, reason: str | None = None, **goal: Any) -> Trace:
        self.add("goal", goal_uuid=uuid(n), goal={"dynamic_event_seq": 1, **goal})
        response: dict[str, Any] = {"goal_uuid": uuid(n), "accepted": accepted}
        if reason is not None:
            response["reason"] = reason
        return self.add("goal_response", **response)

    def next(self, n: int, event_id: int, accepted: bool = True, **goal: Any) -> Trace:
        fields = {
            "event_type": 1,
            "category": "go_to_place",
            "description": '"pantry"',
            "id": event_id,
            **goal,
        }
        return self.goal(n, accepted, **fields)

    def feedback(self, n: int, status: str, event_id: int, logs: tuple[int, ...] = ()) -> Trace:
        entries = [{"seq": seq, "tier": "info", "unix_millis_time": 0, "text": "moving"} for seq in logs]
        return self.add(
            "feedback", goal_uuid=uuid(n), feedback={"status": status, "id": event_id, "logs": entries}
        )

    def result(self, n: int, status: str, final: str = "", event_id: int = 0, failure: str = "") -> Trace:
        result = {"execution_failure": failure, "status": final, "id": event_id}
        return self.add("result", goal_uuid=uuid(n), status=status, result=result)

    def started(self) -> Trace:
        """Run 1 (event 5) with NEXT 6 running."""
        self.begin().status(1, 1, "standby", 5)
        return self.next(1, 6).feedback(1, "underway", 6).status(1, 2, "underway", 6)

    def text(self) -> str:
        return "".join(_json.dumps(row) + "\n" for row in self.rows)

    def check(self) -> Report:
        return check_trace(self.text(), "t.jsonl")

    @property
    def line(self) -> int:
        """The line of the last record."""
        return len(self.rows)


def found(report: Report) -> list[tuple[int, str, str]]:
    return [(finding.line, finding.rule, finding.code) for finding in report.findings]


# --------------------------------------------------------------------------- clean traces


def test_the_clean_example_is_clean() -> None:
    report = check_trace((EXAMPLES / "clean-trace.jsonl").read_text(encoding="utf-8"), "clean")
    assert report.clean and report.records == 36


def test_a_whole_run_is_clean() -> None:
    trace = Trace().started().feedback(1, "underway", 6, logs=(0,)).feedback(1, "delayed", 6, logs=(1,))
    trace.status(1, 2, "delayed", 6).result(1, "succeeded", "completed", 6).status(1, 1, "standby", 6)
    trace.goal(2, event_type=3).result(2, "succeeded", "completed", 5).status(1, 0, "uninitialized", 0)
    assert trace.check().clean


_KINDS = {"begin": 3, "goal": 8, "start": 7, "progress": 4, "finish": 3, "cancel": 2}
_KINDS |= {"task_cancel": 1, "task_kill": 1, "interrupt": 1, "resume": 1, "tick": 1}
_STATUSES = [
    "underway",
    "delayed",
    "blocked",
    "completed",
    "failed",
    "canceled",
    "skipped",
    "queued",
    "error",
]


def _random_session(rng: random.Random, steps: int) -> list[dict[str, Any]]:
    """Records of a server driven by random inputs, as a tap at the server writes them."""
    config = machine.ServerConfig(categories={"go_to_place": machine.any_description})
    state = machine.State.new("tinyRobot", "tinyRobot1")
    rows: list[dict[str, Any]] = []
    now = 0
    for count in range(steps):
        now += rng.randint(1, 3) * 100_000_000
        kind = rng.choices(list(_KINDS), weights=list(_KINDS.values()))[0]
        if count == steps - 1 and rng.random() < 0.3:
            kind = "shutdown"
        event: ins.Input | None = None
        if kind == "begin":
            event = ins.Begin(description="{}", event_id=rng.choice([0, 5, 20]), now=now)
        elif kind == "goal":
            running = state.running.child_id if state.running else state.last_id
            goal = Goal(
                dynamic_event_seq=rng.choice([state.seq, state.seq, (state.seq - 1) % 2**32]),
                event_type=rng.choice([1, 1, 1, 2, 2, 3, 0, 7]),
                category=rng.choice(["go_to_place", "go_to_place", "dance"]),
                description=rng.choice(['"p"', '"p"', "nope"]),
                id=rng.choice([state.last_id + 1, state.last_id + 2, running, 3]),
                stubborn_period=rng.choice([0.0, 0.5]),
            )
            event = ins.GoalRequested(goal_uuid=uuid(count + 1), goal=goal, now=now)
        elif kind == "start" and state.queued:
            queued = state.queued[0] if rng.random() < 0.7 else rng.choice(state.queued)
            event = ins.GoalStarted(goal_uuid=queued.goal_uuid, now=now)
        elif kind == "cancel":
            open_goals = [item.goal_uuid for item in state.queued] + list(state.cancels)
            if state.running is not None:
                open_goals.append(state.running.goal_uuid)
            event = ins.CancelRequested(goal_uuid=rng.choice([*open_goals, uuid(999)]), now=now)
        elif kind == "progress":
            event = ins.ChildProgress(
                status=rng.choice(_STATUSES), now=now, log_text=rng.choice([None, "hi"])
            )
        elif kind == "finish":
            event = ins.ChildFinished(status=rng.choice(_STATUSES), now=now)
        elif kind == "tick":
            event = ins.Tick(now=now, map_name="L1", x=rng.random(), y=0.0)
        elif kind in ("task_cancel", "task_kill", "interrupt", "resume", "shutdown"):
            event = ins.INPUT_TYPES[kind](now=now)  # type: ignore[call-arg]
        if event is None:
            continue
        transition = machine.step(state, event, config)
        state = transition.state
        rows.extend(step_records(event, transition.outputs))
    return rows


@pytest.mark.parametrize("with_config", [True, False])
def test_every_trace_a_server_writes_is_clean(with_config: bool) -> None:
    """Observer mode explains whatever the machine does: random sessions, whole or from a status on."""
    for seed in range(150):
        rng = random.Random(seed)
        rows = _random_session(rng, 60)
        statuses = [index for index, row in enumerate(rows) if row["type"] == "status"]
        variants = [rows, rows[rng.choice(statuses) :]] if statuses else [rows]
        for variant in variants:
            head = [CONFIG] if with_config else []
            text = "".join(_json.dumps(row) + "\n" for row in head + variant)
            report = check_trace(text, f"seed {seed}")
            assert report.clean, (seed, report.findings[:3])


# --------------------------------------------------------------------------- one trace per violation


def test_a_goal_accepted_with_a_stale_seq() -> None:
    trace = Trace().begin().status(1, 1, "standby", 5).next(1, 6, dynamic_event_seq=0)
    assert found(trace.check()) == [(trace.line, "R4.2", "accepted_seq_mismatch")]


def test_a_next_accepted_while_busy() -> None:
    trace = Trace().started().next(2, 7)
    assert found(trace.check()) == [(trace.line, "R4.6", "accepted_busy")]


def test_a_goal_accepted_while_inactive() -> None:
    trace = Trace().next(1, 6, dynamic_event_seq=0)
    assert found(trace.check()) == [(trace.line, "R4.3", "accepted_inactive")]


def test_a_goal_refused_that_passes_every_check() -> None:
    trace = Trace().begin().status(1, 1, "standby", 5).next(1, 6, accepted=False)
    assert found(trace.check()) == [(trace.line, "R4.16", "rejected_acceptable")]


def test_a_refusal_without_a_config_may_be_the_categories() -> None:
    trace = Trace(config=False).begin().status(1, 1, "standby", 5).next(1, 6, accepted=False)
    assert trace.check().clean


def test_a_refusal_with_the_wrong_reason() -> None:
    trace = Trace().started().goal(2, accepted=False, reason="cancel_idle", event_type=2, id=9)
    assert found(trace.check()) == [(trace.line, "R4.14", "wrong_reason")]


def test_a_second_terminal_answer() -> None:
    trace = Trace().started().result(1, "succeeded", "completed", 6).status(1, 1, "standby", 6)
    trace.result(1, "aborted", "canceled", 6)
    assert found(trace.check()) == [(trace.line, "R19.1", "second_answer")]


def test_an_answer_to_a_rejected_goal() -> None:
    trace = Trace().started().next(2, 7, accepted=False).result(2, "aborted", failure="race condition")
    assert found(trace.check()) == [(trace.line, "R19.1", "answer_not_accepted")]


@pytest.mark.spec("R19.1", "R8.2", "R8.4")
def test_a_childs_end_shown_by_its_status_alone_owes_the_answer() -> None:
    """A WAITING status shows the running child's end; no answer comes: the answer is missing (R19.1),
    at that status, and nothing else is found.  An answer that comes late is taken, whatever it says
    (how the child ended is not on the wire)."""
    missing = Trace().started().status(1, 1, "standby", 6)
    at_end = missing.line
    missing.status(1, 0, "uninitialized", 0)  # the run goes on without it (a FINISHED, unseen)
    assert found(missing.check()) == [(at_end, "R19.1", "answer_missing")]
    late = Trace().started().status(1, 1, "standby", 6).next(2, 7).feedback(2, "underway", 7)
    late.result(1, "aborted", "skipped", 6)  # three records on: past the lookahead
    assert late.check().clean, found(late.check())


@pytest.mark.spec("R8.1")
def test_an_answer_after_the_status_of_its_childs_end_still_names_the_child_and_an_ended_status() -> None:
    """Seen over DDS: a client hears the WAITING status of a child's end before the child's answer.
    How the child ended is not on the wire, but what the answer's result must name is (R8.1): the
    child's id and an ended status.  A result naming neither is a finding; one naming both is not."""
    good = Trace().started().status(1, 1, "standby", 6).result(1, "succeeded", "completed", 6)
    assert good.check().clean, found(good.check())
    bad = Trace().started().status(1, 1, "standby", 6).result(1, "succeeded", "", 0)
    assert found(bad.check()) == [(bad.line, "R8.1", "result")]


@pytest.mark.spec("R4.6", "R11.1")
def test_a_finished_accepted_after_the_status_of_the_childs_end_may_have_come_after_that_end() -> None:
    """Seen at a client across a lossy link: a FINISHED sent while a child ran, its response heard
    after the status of the child's end and the child's answer.  Its request may have reached the
    server after that end (a lost request is sent again, seconds later), where the server rightly
    accepts it: no finding.  A FINISHED accepted before the child's end is heard still is one (R4.6)."""

    def trace(response_first: bool) -> Trace:
        finished = {"dynamic_event_seq": 1, "event_type": 3, "category": "", "description": "", "id": 0}
        talk = Trace()
        talk.rows[0] = {**talk.rows[0], "tap": "client"}
        talk.started().add("goal", goal_uuid=uuid(2), goal=finished)
        if response_first:
            talk.add("goal_response", goal_uuid=uuid(2), accepted=True)
        talk.status(1, 1, "standby", 6).result(1, "succeeded", "completed", 6)
        if not response_first:
            talk.add("goal_response", goal_uuid=uuid(2), accepted=True)
        return talk.result(2, "succeeded", "completed", 5).status(1, 0, "uninitialized", 0)

    late = trace(response_first=False)
    assert late.check().clean, found(late.check())
    assert [finding[1:] for finding in found(trace(response_first=True).check())][:1] == [
        ("R4.6", "accepted_busy")
    ]


@pytest.mark.spec("R6.4", "R2.2")
def test_a_child_whose_start_a_client_never_saw_is_read_from_its_end() -> None:
    """Seen at a client across a lossy link: a NEXT accepted, then nothing of its child's start (the
    status that showed it running was taken over by the next, the status topic keeping one message,
    and its feedback was lost for good), then the status of its end and its answer: the child started
    and ended, no finding.  Seen at the server, where every record is kept, the same records are
    findings: a status of a child that never started (R2.2), and its answer (R6.4)."""

    def trace(tap: str, *, answered: bool = True) -> Trace:
        talk = Trace()
        talk.rows[0] = {**talk.rows[0], "tap": tap}
        talk.started().result(1, "succeeded", "completed", 6).status(1, 1, "standby", 6)
        talk.next(2, 7).status(1, 1, "standby", 7)
        return talk.result(2, "succeeded", "completed", 7) if answered else talk.status(1, 1, "standby", 7)

    assert trace("client").check().clean, found(trace("client").check())
    server = [finding[1:] for finding in found(trace("server").check())]
    assert server == [("R2.2", "status_mismatch"), ("R6.4", "unexpected_answer")], server
    unanswered = [finding[1:] for finding in found(trace("client", answered=False).check())]
    assert ("R2.2", "status_mismatch") in unanswered, unanswered


@pytest.mark.spec("R6.4", "R2.2")
def test_a_childs_feedback_a_client_heard_after_the_status_of_its_end_was_sent_before_it() -> None:
    """Seen at a client across a lossy link: a NEXT accepted, the status that showed its child running
    lost (taken over by the next), then the status of the child's end, and only then the child's start
    feedback, a progress feedback and its answer (feedback sent again, late): the feedback was sent
    before that status (R6.4: a child's start feeds back first), no finding."""
    talk = Trace()
    talk.rows[0] = {**talk.rows[0], "tap": "client"}
    talk.started().result(1, "succeeded", "completed", 6).status(1, 1, "standby", 6)
    talk.next(2, 7).status(1, 1, "standby", 7)
    talk.feedback(2, "underway", 7).feedback(2, "underway", 7, logs=(1,))
    talk.result(2, "succeeded", "completed", 7)
    assert talk.check().clean, found(talk.check())


def _racing_nexts() -> Trace:
    """Seen at a client: run 1 waiting at event 5, then NEXTs 6 (goal 1) and 7 (goal 2) sent at once."""
    nexts = {"event_type": 1, "category": "go_to_place", "description": '"pantry"'}
    talk = Trace()
    talk.rows[0] = {**talk.rows[0], "tap": "client"}
    talk.begin().status(1, 1, "standby", 5)
    talk.add("goal", goal_uuid=uuid(1), goal={"dynamic_event_seq": 1, **nexts, "id": 6})
    return talk.add("goal", goal_uuid=uuid(2), goal={"dynamic_event_seq": 1, **nexts, "id": 7})


@pytest.mark.spec("R5.2", "R4.6")
def test_a_racing_next_whose_child_a_client_saw_start_after_the_others_end_came_after_that_end() -> None:
    """Seen at a client across a lossy link: two NEXTs sent at once; the first runs its child to the
    end, and only then do the second's start feedback, the status of its child and its response come
    (its request was lost and sent again, seconds later).  The server took the second after the first
    child's end, rightly: no finding.  Read as accepted beside the first (its response moved back to
    its request, or before the first child's status), it would have lost the race (R5.2)."""
    talk = _racing_nexts()
    talk.add("goal_response", goal_uuid=uuid(1), accepted=True)
    talk.feedback(1, "underway", 6).status(1, 2, "underway", 6)
    talk.status(1, 1, "standby", 6).result(1, "succeeded", "completed", 6)
    talk.feedback(2, "underway", 7).status(1, 2, "underway", 7)
    talk.add("goal_response", goal_uuid=uuid(2), accepted=True)
    talk.status(1, 1, "standby", 7).result(2, "succeeded", "completed", 7)
    assert talk.check().clean, found(talk.check())


@pytest.mark.spec("R9.1", "R9.2")
def test_a_cancel_a_client_heard_answered_after_the_next_child_started_had_stopped_its_child() -> None:
    """Seen at a client across a lossy link: a CANCEL of the running child sent, the child answered
    canceled and the robot waiting again, then the next NEXT's child started (and ended, and a CANCEL
    of it was refused), and only then the CANCEL's response and its answer (the link sent both
    again, seconds late).  The CANCEL reached the server at once and stopped its child (R9.1): no
    finding.  Read as still queued when the child ended, it would have started while the next child
    ran, and its answer would be owed as the mismatch (R9.2)."""
    talk = Trace()
    talk.rows[0] = {**talk.rows[0], "tap": "client"}
    talk.started().add("goal", goal_uuid=uuid(2), goal={"dynamic_event_seq": 1, "event_type": 2, "id": 6})
    talk.result(1, "aborted", "canceled", 6).status(1, 1, "standby", 6)
    fields = {"event_type": 1, "category": "go_to_place", "description": '"pantry"', "id": 7}
    talk.add("goal", goal_uuid=uuid(3), goal={"dynamic_event_seq": 1, **fields})
    talk.feedback(3, "underway", 7).status(1, 2, "underway", 7)
    talk.add("goal_response", goal_uuid=uuid(2), accepted=True)
    talk.add("goal_response", goal_uuid=uuid(3), accepted=True).status(1, 1, "standby", 7)
    talk.add("goal", goal_uuid=uuid(4), goal={"dynamic_event_seq": 1, "event_type": 2, "id": 7})
    talk.add("goal_response", goal_uuid=uuid(4), accepted=False)  # child 7 has ended (R4.13)
    talk.result(2, "succeeded", "canceled", 6).result(3, "succeeded", "completed", 7)
    assert talk.check().clean, found(talk.check())


@pytest.mark.spec("R5.2")
def test_a_race_a_client_heard_lost_before_it_heard_either_nexts_response_or_the_winners_start() -> None:
    """Seen at a client whose responses lag: two NEXTs sent at once, both accepted, the first started
    and the second lost the race (aborted, race condition); the client hears that answer first, then
    the first child's status, the two responses, and the first child's feedback.  The NEXT accepted
    first started first, and the other's answer comes by a service of its own, in no order with the
    first's feedback: no finding."""
    talk = _racing_nexts()
    talk.result(2, "aborted", "", 0, failure="race condition").status(1, 2, "underway", 6)
    talk.add("goal_response", goal_uuid=uuid(1), accepted=True)
    talk.add("goal_response", goal_uuid=uuid(2), accepted=True)
    talk.feedback(1, "underway", 6).result(1, "succeeded", "completed", 6).status(1, 1, "standby", 6)
    assert talk.check().clean, found(talk.check())


def _stamped_status(talk: Trace, phase: int, status: str, event_id: int, at: float) -> None:
    """A status of run 1 the server stamped ``at`` (seconds)."""
    stamp = {"sec": int(at), "nanosec": round((at - int(at)) * 1e9)}
    message = {
        "dynamic_event_seq": 1,
        "dynamic_state": phase,
        "status": status,
        "id": event_id,
        "time": stamp,
    }
    talk.add("status", message=message)


def _next_request(talk: Trace, n: int, event_id: int) -> None:
    """Goal ``n``'s request: a NEXT of run 1 with id ``event_id``, no response."""
    talk.add("goal", goal_uuid=uuid(n), goal={"dynamic_event_seq": 1, "event_type": 1,
             "category": "go_to_place", "description": '"pantry"', "id": event_id})  # fmt: skip


def _next_awaiting(tap: str = "client") -> Trace:
    """A trace at ``tap``: run 1 begun, its status standby (event 5), and NEXT 1 (id 6) requested, its
    response not (yet) heard."""
    talk = Trace()
    talk.rows[0] = {**talk.rows[0], "tap": tap}
    talk.begin()
    _stamped_status(talk, 1, "standby", 5, 100.0)
    _next_request(talk, 1, 6)
    return talk


def _logged_feedback(talk: Trace, n: int, event_id: int, seq: int, at: float) -> None:
    """Goal ``n``'s feedback carrying log entry ``seq``, made ``at`` (seconds)."""
    entry = {"seq": seq, "tier": "info", "unix_millis_time": round(at * 1000), "text": "moving"}
    feedback = {"status": "underway", "id": event_id, "logs": [entry]}
    talk.add("feedback", goal_uuid=uuid(n), feedback=feedback)


@pytest.mark.spec("R6.4", "R8.2", "R19.1")
def test_a_goal_whose_response_a_client_never_heard_is_read_as_accepted_from_its_feedback() -> None:
    """Seen at a client whose link lost a NEXT's response for good (and its answer), and delivered
    feedback the server made before the status of the child's end after that status: the server
    feeds back only a goal it accepted, so the goal is read as accepted at its first feedback, and
    the late feedback as sent before the status (their stamps are the server's).  The answer never
    came: missing, but as an open item of the judge (``answer_lost``), since the client that lost the
    response may have lost the answer the same way."""
    talk = _next_awaiting()
    talk.feedback(1, "underway", 6)
    _stamped_status(talk, 2, "underway", 6, 101.0)
    _logged_feedback(talk, 1, 6, 0, 102.0)
    _stamped_status(talk, 1, "standby", 6, 106.0)  # the child's end
    for seq in (1, 2, 3):
        _logged_feedback(talk, 1, 6, seq, 102.0 + seq)  # made before that status, delivered after it
    report = talk.check()
    assert [(finding.rule, finding.code, finding.detail) for finding in report.findings] == [
        ("R19.1", "answer_missing", "response_unheard")
    ], found(report)
    assert divergences.label(report.findings[0]) == "answer_lost"
    assert divergences.label(report.findings[0]) in divergences.OPEN_ITEMS


@pytest.mark.spec("R2.2", "R6.4", "R11.1", "R19.1")
@pytest.mark.parametrize("tap", ["client", "server"])
def test_statuses_heard_of_goals_whose_responses_never_came_are_read_as_their_starts(tap: str) -> None:
    """Seen at a client across a link that held the action's responses back (found at 30% loss: a
    NEXT's and a FINISHED's responses never heard, their statuses heard at once): the status of the
    NEXT's child running, heard before any of its feedback, is its start, the goal read as accepted;
    the start feedback and a report made before the status of the child's end, both delivered after
    it, go before it (feedback comes in the order sent); the INACTIVE status is the FINISHED's end of
    the run.  Only the NEXT's answer is missing, as an open item (``answer_lost``).  At the server's
    own tap nothing is held back: the statuses of goals never responded to disagree with the state."""
    talk = _next_awaiting(tap)
    _stamped_status(talk, 2, "underway", 6, 101.0)  # before any feedback of the child
    running = talk.line
    _stamped_status(talk, 1, "standby", 6, 108.0)  # its end
    talk.feedback(1, "underway", 6)  # its start, delivered late
    _logged_feedback(talk, 1, 6, 0, 102.0)  # made before the end's status, delivered after it
    talk.add("goal", goal_uuid=uuid(2), goal={"dynamic_event_seq": 1, "event_type": 3})
    _stamped_status(talk, 0, "uninitialized", 0, 109.0)  # the FINISHED's end of the run
    report = talk.check()
    if tap == "client":
        assert [(finding.rule, finding.code, finding.detail) for finding in report.findings] == [
            ("R19.1", "answer_missing", "response_unheard")
        ], found(report)
        assert divergences.label(report.findings[0]) in divergences.OPEN_ITEMS
    else:
        assert (running, "R2.2", "status_mismatch") in found(report), found(report)


@pytest.mark.spec("R19.1")
@pytest.mark.parametrize("accepted", [True, False])
def test_a_response_heard_after_its_goal_was_read_as_accepted_from_its_start(accepted: bool) -> None:
    """Seen at a client: a NEXT's response held back past the records the judge looks ahead (a lossy
    link sent it again 30 s late), its start and answer heard long before, so that the goal was read
    as accepted.  An acceptance heard then agrees; a refusal contradicts the start the server
    showed (R19.1 response_mismatch).  Neither is a record the trace cannot hold."""
    talk = _next_awaiting()
    talk.feedback(1, "underway", 6)
    _stamped_status(talk, 2, "underway", 6, 101.0)
    talk.result(1, "succeeded", "completed", 6)
    _stamped_status(talk, 1, "standby", 6, 102.0)
    for _ in range(CLIENT_LOOKAHEAD):  # the latched status, read again by late subscribers
        _stamped_status(talk, 1, "standby", 6, 102.0)
    talk.add("goal_response", goal_uuid=uuid(1), accepted=accepted)
    late = talk.line
    report = talk.check()
    expected = [] if accepted else [(late, "R19.1", "response_mismatch")]
    assert found(report) == expected


@pytest.mark.spec("R4.13", "R5.1", "R19.1")
def test_a_status_is_not_read_as_the_start_of_a_goal_a_state_since_its_request_refused() -> None:
    """Seen at a client: a NEXT sent while child 6 ran (refused busy), the same NEXT sent again after
    that child's end, and the status of child 7 running heard before either response, both held
    back past the records looked ahead.  The first request met a state that refuses it, so the
    status is the second's start; the refusal and the acceptance heard late agree with that."""
    talk = Trace()
    talk.rows[0] = {**talk.rows[0], "tap": "client"}
    talk.begin()
    _stamped_status(talk, 1, "standby", 5, 100.0)
    talk.next(1, 6).feedback(1, "underway", 6)
    _stamped_status(talk, 2, "underway", 6, 101.0)
    _next_request(talk, 2, 7)  # while child 6 runs: refused busy
    talk.result(1, "succeeded", "completed", 6)
    _stamped_status(talk, 1, "standby", 6, 102.0)
    _next_request(talk, 3, 7)  # again, after the end: accepted
    _stamped_status(talk, 2, "underway", 7, 103.0)
    talk.feedback(3, "underway", 7).result(3, "succeeded", "completed", 7)
    _stamped_status(talk, 1, "standby", 7, 104.0)
    for _ in range(CLIENT_LOOKAHEAD):  # the latched status, read again by late subscribers
        _stamped_status(talk, 1, "standby", 7, 104.0)
    talk.add("goal_response", goal_uuid=uuid(2), accepted=False, reason="busy")
    talk.add("goal_response", goal_uuid=uuid(3), accepted=True)
    assert found(talk.check()) == []


@pytest.mark.spec("R19.1")
def test_a_goal_read_as_accepted_from_its_start_is_missing_its_response_in_a_trace_heard_out() -> None:
    """A trace that ends heard out (its end record): a NEXT whose child ran and was answered, its
    response never heard.  At a client it was read as accepted from its start, and is still missing
    its response (R19.1: a server responds in the step that takes a request)."""
    talk = _next_awaiting()
    request = talk.line
    _stamped_status(talk, 2, "underway", 6, 101.0)
    talk.feedback(1, "underway", 6).result(1, "succeeded", "completed", 6)
    _stamped_status(talk, 1, "standby", 6, 102.0)
    talk.add("end")
    assert found(talk.check()) == [(request, "R19.1", "response_missing")]


@pytest.mark.spec("R4.13", "R4.16")
def test_a_cancel_refused_at_a_client_before_it_hears_the_childs_end_may_have_come_after_that_end() -> None:
    """Seen at a client across a lossy link: a CANCEL of the running child, delivered after the child's
    end, rightly refused (R4.13: no child runs), the refusal heard before the status of that end and
    the child's answer.  At a client it is read as reaching the server after the end whose answer is
    ahead: no finding.  A refusal for a reason that end does not give, or seen at the server, where a
    response follows its request at once, is still one (R4.16)."""

    def trace(tap: str, reason: str | None) -> Trace:
        cancel = {"dynamic_event_seq": 1, "event_type": 2, "category": "", "description": "", "id": 6}
        talk = Trace()
        talk.rows[0] = {**talk.rows[0], "tap": tap}
        talk.started().add("goal", goal_uuid=uuid(2), goal=cancel)
        refusal: dict[str, Any] = {"goal_uuid": uuid(2), "accepted": False}
        talk.add("goal_response", **(refusal if reason is None else {**refusal, "reason": reason}))
        return talk.status(1, 1, "standby", 6).result(1, "succeeded", "completed", 6)

    for reason in (None, "cancel_idle"):
        late = trace("client", reason)
        assert late.check().clean, (reason, found(late.check()))
    for tap, reason in (("client", "busy"), ("server", None)):
        assert [finding[1:] for finding in found(trace(tap, reason).check())] == [
            ("R4.16", "rejected_acceptable")
        ]


@pytest.mark.spec("R4.6", "R4.16")
def test_a_finished_refused_busy_by_a_child_a_client_heard_run_between_its_request_and_response() -> None:
    """Seen at a client across a lossy link: a NEXT whose response was lost and whose child the client
    heard start only after it sent a FINISHED (the NEXT's request reached the server late), then that
    child's end, then the FINISHED's refusal, busy (R4.6): the FINISHED reached the server while the
    child ran.  At a client, a refusal that a state between the request and its response gives is no
    finding.  Requested after the client heard the child's end, or seen at the server, or refused for
    a reason no state between gives, it is still one (R4.16)."""

    def trace(tap: str, reason: str = "busy", request_first: bool = True) -> Trace:
        finished = {"dynamic_event_seq": 1, "event_type": 3, "category": "", "description": "", "id": 0}
        nxt = {
            "dynamic_event_seq": 1,
            "event_type": 1,
            "category": "go_to_place",
            "description": '"pantry"',
            "id": 6,
        }
        talk = Trace()
        talk.rows[0] = {**talk.rows[0], "tap": tap}
        talk.begin().status(1, 1, "standby", 5).add("goal", goal_uuid=uuid(1), goal=nxt)
        if request_first:
            talk.add("goal", goal_uuid=uuid(2), goal=finished)
        talk.feedback(1, "underway", 6).status(1, 2, "underway", 6)
        talk.status(1, 1, "standby", 6).result(1, "succeeded", "completed", 6)
        if not request_first:
            talk.add("goal", goal_uuid=uuid(2), goal=finished)
        return talk.add("goal_response", goal_uuid=uuid(2), accepted=False, reason=reason)

    late = trace("client")
    assert late.check().clean, found(late.check())
    for tap, reason, request_first in (
        ("server", "busy", True),
        ("client", "busy", False),
        ("client", "cancel_idle", True),
    ):
        findings = [finding[1:] for finding in found(trace(tap, reason, request_first).check())]
        assert ("R4.16", "rejected_acceptable") in findings, (tap, reason, request_first, findings)


@pytest.mark.spec("R5.2", "R4.6")
def test_a_next_a_lossy_link_delivered_after_the_other_nexts_child_ended_is_a_fresh_next() -> None:
    """Found at 30% loss across hosts (next.race): two NEXTs sent at once, the second delivered late,
    after the first's child had ended (the status of that end overwritten on the status topic, the
    first's answer heard last).  The server took the second as a fresh NEXT and ran its child: at a
    client, a NEXT accepted while the state still runs a child whose answer is that child's next
    record is read as reaching the server after that end; no race lost, no finding.  Where a report
    of the first child comes after the second's acceptance (it still ran), or at the server's tap,
    it is still one."""

    def trace(tap: str, still_running: bool = False) -> Trace:
        talk = Trace()
        talk.rows[0] = {**talk.rows[0], "tap": tap}
        talk.begin().status(1, 1, "standby", 5)
        for n, event_id in ((1, 6), (2, 7)):
            nxt = {
                "dynamic_event_seq": 1,
                "event_type": 1,
                "category": "go_to_place",
                "description": '"pantry"',
            }
            talk.add("goal", goal_uuid=uuid(n), goal={**nxt, "id": event_id})
        talk.status(1, 2, "underway", 6).feedback(1, "underway", 6).feedback(1, "underway", 6, logs=(1,))
        talk.add("goal_response", goal_uuid=uuid(1), accepted=True)
        talk.feedback(2, "underway", 7).status(1, 2, "underway", 7)
        talk.add("goal_response", goal_uuid=uuid(2), accepted=True)
        if still_running:
            talk.feedback(1, "underway", 6, logs=(2,))
        talk.feedback(2, "underway", 7, logs=(3 if still_running else 2,)).status(1, 1, "standby", 7)
        return talk.result(1, "succeeded", "completed", 6).result(2, "succeeded", "completed", 7)

    late = trace("client")
    assert late.check().clean, found(late.check())
    for tap, still_running in (("server", False), ("client", True)):
        assert found(trace(tap, still_running).check()), (tap, still_running)


@pytest.mark.spec("R10.3")
def test_an_action_level_cancel_refused_after_a_client_hears_its_goals_answer_may_have_come_after_it() -> (
    None
):
    """Seen at a client across a lossy link: an action-level cancel of the running NEXT, sent while its
    child ran, its refusal heard after the child's end and the NEXT's answer (succeeded: the cancel
    did not stop it).  Its request may have reached the server after that answer (a lost request is
    sent again, seconds later), where a server rightly refuses it: no finding.  Refused before the
    answer is heard, or seen at the server, or after an answer that says the cancel stopped the child
    (the cancel reached the server while the child ran), it is still one (R10.3)."""

    def trace(tap: str, answer_first: bool, child: str = "completed") -> Trace:
        talk = Trace()
        talk.rows[0] = {**talk.rows[0], "tap": tap}
        talk.started().add("cancel_request", goal_uuid=uuid(1))
        if not answer_first:
            talk.add("cancel_response", goal_uuid=uuid(1), accepted=False)
        answer = "succeeded" if child == "completed" else "aborted"
        talk.status(1, 1, "standby", 6).result(1, answer, child, 6)
        if answer_first:
            talk.add("cancel_response", goal_uuid=uuid(1), accepted=False)
        return talk

    late = trace("client", answer_first=True)
    assert late.check().clean, found(late.check())
    for tap, answer_first, child in (
        ("client", False, "completed"),
        ("server", True, "completed"),
        ("client", True, "canceled"),
    ):
        findings = [finding[1:] for finding in found(trace(tap, answer_first, child).check())]
        assert ("R10.3", "cancel_response") in findings, (tap, answer_first, child, findings)


@pytest.mark.spec("R10.5", "R10.3")
@pytest.mark.parametrize("tap", ["client", "server"])
def test_a_cancel_refused_as_of_a_goal_terminated_came_after_the_goals_end(tap: str) -> None:
    """Found in the lab: the running child ended as the action-level cancel of its NEXT came, and the
    server refused the cancel because the goal had terminated (``terminated``: ROS 2's
    ``ERROR_GOAL_TERMINATED``), its answer and the status of the child's end recorded after the
    refusal.  The goal had ended before the request: the refusal is right (R10.5), at either tap.
    Refused without ``terminated``, the server refused an open goal's cancel: R10.3."""

    def trace(terminated: bool) -> Trace:
        talk = Trace()
        talk.rows[0] = {**talk.rows[0], "tap": tap}
        talk.started().add("cancel_request", goal_uuid=uuid(1))
        refusal = {"terminated": True} if terminated else {}
        talk.add("cancel_response", goal_uuid=uuid(1), accepted=False, **refusal)
        return talk.status(1, 1, "standby", 6).result(1, "succeeded", "completed", 6)

    assert trace(terminated=True).check().clean, found(trace(terminated=True).check())
    findings = [finding[1:] for finding in found(trace(terminated=False).check())]
    assert ("R10.3", "cancel_response") in findings, findings


@pytest.mark.spec("R10.1", "R10.3")
def test_an_action_level_cancel_sent_as_a_goal_is_accepted_finds_it_queued_or_started() -> None:
    """A client cancels a NEXT as soon as it hears the NEXT accepted.  A server that had not started it
    answers it ``cancelled while not running`` (R10.1), with no feedback; one that starts a goal with
    its acceptance (dynevent's ROS binding) had started it, and cancels its child (R10.3): at a
    client, the start's feedback and status may come after the cancel's request, and its answer
    shows it ran.  At the server's tap, records come in the server's order: a cancel before any sign
    of the start found the goal queued, and an answer of a child's end is the server's fault."""

    def trace(tap: str, started: bool) -> Trace:
        talk = Trace()
        talk.rows[0] = {**talk.rows[0], "tap": tap}
        talk.begin().status(1, 1, "standby", 5).next(1, 6)
        talk.add("cancel_request", goal_uuid=uuid(1)).add("cancel_response", goal_uuid=uuid(1), accepted=True)
        if not started:
            return talk.result(1, "canceled", failure="cancelled while not running")
        talk.feedback(1, "underway", 6).status(1, 2, "underway", 6)
        return talk.result(1, "canceled", "canceled", 6).status(1, 1, "standby", 6)

    for tap, started in (("client", False), ("client", True), ("server", False)):
        assert trace(tap, started).check().clean, (tap, started, found(trace(tap, started).check()))
    assert found(trace("server", started=True).check())


@pytest.mark.spec("R10.3", "R10.1")
def test_a_cancelled_next_whose_answer_shows_its_child_ran_had_started_though_no_start_was_heard() -> None:
    """Found at 30% loss across hosts: a client cancels a NEXT as soon as it hears it accepted; the
    server had started it (R10.3) and answers it ``canceled`` with its child's id and status, but
    the start's feedback and the RUNNING status were lost for good.  Seen apart, that answer shows
    the goal had started when the cancel came (one cancelled before its start is answered
    ``cancelled while not running``, R10.1).  At the server's tap, the goal was queued: R10.1's."""

    def trace(tap: str) -> Trace:
        talk = Trace()
        talk.rows[0] = {**talk.rows[0], "tap": tap}
        talk.begin().status(1, 1, "standby", 5).next(1, 6)
        talk.add("cancel_request", goal_uuid=uuid(1)).add("cancel_response", goal_uuid=uuid(1), accepted=True)
        return talk.result(1, "canceled", "canceled", 6).status(1, 1, "standby", 6)

    assert trace("client").check().clean, found(trace("client").check())
    assert ("R10.1", "result_id") in [finding[1:] for finding in found(trace("server").check())]


@pytest.mark.spec("R4.13", "R4.16", "R8.2")
def test_a_cancel_refused_at_a_client_before_late_reports_of_the_child_may_have_come_after_its_end() -> None:
    """Found at 30% loss across hosts: the probe's CANCEL of child 6 reached the server as the child
    ended, and was refused (no child runs, R4.13); the client heard the refusal, then six reports the
    child had sent before its end, delivered late, then the end.  Seen apart, the refusal is read as
    after the end and the reports as sent before it; at the server's tap, where the order is the
    server's, the refusal came while the child ran (R4.16)."""

    def trace(tap: str) -> Trace:
        talk = Trace()
        talk.rows[0] = {**talk.rows[0], "tap": tap}
        talk.started().goal(2, accepted=False, event_type=2, id=6)
        talk.feedback(1, "underway", 6, logs=(0,)).feedback(1, "underway", 6, logs=(1,))
        return talk.status(1, 1, "standby", 6).result(1, "succeeded", "completed", 6)

    assert trace("client").check().clean, found(trace("client").check())
    assert ("R4.16", "rejected_acceptable") in [finding[1:] for finding in found(trace("server").check())]


@pytest.mark.spec("R11.1")
def test_a_run_whose_begins_own_status_a_client_never_heard_has_an_own_id_its_finished_tells() -> None:
    """Found leaving a message out of a lossy recording: the run's begin read latched, its WAITING
    status (naming the run's own id, 5) lost, a child run and ended.  The WAITING status after that
    child names the highest id used, not the run's own: the FINISHED's answer tells it, and is not
    held to the begin's placeholder id.  Where the begin's status was heard, the id it named is
    still held to."""

    def trace(heard: bool, own: int = 5) -> Trace:
        talk = Trace()
        talk.rows[0] = {**talk.rows[0], "tap": "client"}
        talk.begin(seq=3)
        if heard:
            talk.status(3, 1, "standby", 5)
        talk.next(1, 6, dynamic_event_seq=3).feedback(1, "underway", 6).status(3, 2, "underway", 6)
        talk.result(1, "succeeded", "completed", 6).status(3, 1, "standby", 6)
        talk.goal(2, event_type=3, dynamic_event_seq=3)
        return talk.result(2, "succeeded", "completed", own).status(3, 0, "uninitialized", 0)

    assert trace(heard=False).check().clean, found(trace(heard=False).check())
    assert trace(heard=True).check().clean, found(trace(heard=True).check())
    assert ("R11.1", "result_id") in [finding[1:] for finding in found(trace(heard=True, own=7).check())]


@pytest.mark.spec("R3.3", "R2.2")
def test_a_run_whose_begin_a_client_never_heard_is_read_as_begun_from_its_waiting_status() -> None:
    """Found at 10% loss across hosts: both copies of a run's begin lost for good.  Seen apart, the
    WAITING status of the run after the ended one is read as its begin's; at the server's tap, where
    every begin is seen, it is R2.2."""

    def trace(tap: str) -> Trace:
        talk = Trace()
        talk.rows[0] = {**talk.rows[0], "tap": tap}
        talk.begin().status(1, 1, "standby", 5).goal(1, event_type=3).result(1, "succeeded", "completed", 5)
        talk.status(1, 0, "uninitialized", 0).status(2, 1, "standby", 7)  # run 2's begin unheard
        talk.next(2, 8, dynamic_event_seq=2).feedback(2, "underway", 8).status(2, 2, "underway", 8)
        return talk.result(2, "succeeded", "completed", 8).status(2, 1, "standby", 8)

    assert trace("client").check().clean, found(trace("client").check())
    assert found(trace("server").check())[0] == (8, "R2.2", "status_mismatch")


@pytest.mark.spec("R10.2", "R10.1", "R10.5", "R8.3")
@pytest.mark.parametrize("tap", ["client", "server"])
def test_an_action_level_cancel_of_a_cancel_goal_that_waits_for_the_childs_end(tap: str) -> None:
    """A CANCEL of the running child (6) is accepted, then cancelled at the action level.  Started, it
    waits for the child's end: the cancel answers it ``cancelled while not running`` and the child's
    cancellation goes on, its NEXT aborted ``canceled`` (R10.2, R8.2); no message marks the CANCEL's
    start, and the judge reads the same answers as of a CANCEL not yet started (R10.1).  Refused as of
    a goal terminated: the child had ended and answered the CANCEL (R8.3) before the cancel came, and
    the refusal is right (R10.5), its start unseen; refused otherwise, the CANCEL was open: R10.1."""

    def trace(refusal: dict[str, bool] | None) -> Trace:
        talk = Trace()
        talk.rows[0] = {**talk.rows[0], "tap": tap}
        talk.started().goal(2, event_type=2, id=6).add("cancel_request", goal_uuid=uuid(2))
        if refusal is None:
            talk.add("cancel_response", goal_uuid=uuid(2), accepted=True)
            talk.result(2, "canceled", failure="cancelled while not running")
            return talk.result(1, "aborted", "canceled", 6).status(1, 1, "standby", 6)
        talk.add("cancel_response", goal_uuid=uuid(2), accepted=False, **refusal)
        talk.result(1, "succeeded", "completed", 6).result(2, "succeeded", "completed", 6)
        return talk.status(1, 1, "standby", 6)

    for refusal in (None, {"terminated": True}):
        assert trace(refusal).check().clean, (refusal, found(trace(refusal).check()))
    findings = [finding[1:] for finding in found(trace({}).check())]
    assert ("R10.1", "cancel_response") in findings, findings


@pytest.mark.spec("R10.2", "R9.3")
def test_a_cancel_goals_answer_of_an_action_level_cancel_whose_request_is_lost() -> None:
    """Found at 30% loss across hosts: a recorder heard the action-level cancel of a waiting CANCEL
    33 s late (not judged), and then its answer, ``cancelled while not running``, read as answered
    before its child's end (R9.3).  Seen apart from the server, that answer is R10.2's for a cancel
    whose request the records lack; at the server's tap, which records every cancel it takes, it is
    still R9.3's finding."""

    def trace(tap: str) -> Trace:
        talk = Trace()
        talk.rows[0] = {**talk.rows[0], "tap": tap}
        talk.started().goal(2, event_type=2, id=6)
        talk.result(2, "canceled", failure="cancelled while not running")
        return talk.result(1, "aborted", "canceled", 6).status(1, 1, "standby", 6)

    assert trace("client").check().clean, found(trace("client").check())
    findings = [finding[1:] for finding in found(trace("server").check())]
    assert ("R9.3", "cancel_answered_early") in findings, findings


def test_a_cancel_responses_terminated_is_written_and_read_back() -> None:
    """A probe's trace keeps what the transport said of a refused cancel (the ``terminated`` field)."""
    writer = TraceWriter(None, fleet="f", robot="r", tap="client")
    writer.observe("cancel_response", goal_uuid=uuid(1), accepted=False, terminated=True)
    writer.observe("cancel_response", goal_uuid=uuid(2), accepted=False)
    _, records = read_trace(writer.text().splitlines())
    read = [(record.goal_uuid, record.status) for record in records]
    assert read == [(uuid(1), "terminated"), (uuid(2), "")]


@pytest.mark.spec("R19.1")
def test_the_observer_keeps_the_latest_closed_goals_only_and_still_finds_a_late_second_answer() -> None:
    """Memory stays flat on a trace of any length: of the goals answered or refused, the observer keeps
    the latest CLOSED_GOALS.  A second answer to a goal it let go is still a finding under R19.1 (an
    answer to a goal it does not know); one to a goal it keeps is a second answer."""
    from dynevent.conformance.judge.observer import CLOSED_GOALS, Checker

    trace = Trace().begin().status(1, 1, "standby", 0)
    cycles = CLOSED_GOALS + 50
    for n in range(1, cycles + 1):
        trace.next(n, n).feedback(n, "underway", n).status(1, 2, "underway", n)
        trace.result(n, "succeeded", "completed", n).status(1, 1, "standby", n)
    trace.next(cycles + 1, 0, accepted=False, dynamic_event_seq=0, reason="seq_mismatch")
    trace.result(1, "aborted", "canceled", 1)
    old = trace.line
    trace.result(cycles, "aborted", "canceled", cycles)
    from dynevent.conformance.judge.trace import read_trace

    header, records = read_trace(trace.text().splitlines(keepends=True), "t.jsonl")
    checker = Checker(header)
    for record in records:
        checker.push(record)
    report = checker.finish()
    assert len(checker._observer.rooms.goals) <= CLOSED_GOALS
    assert found(report) == [(old, "R19.1", "answer_not_accepted"), (trace.line, "R19.1", "second_answer")]
    assert report.findings[0].message.endswith(f"or closed before the latest {CLOSED_GOALS} closed goals")


def test_a_judge_seen_apart_reads_states_against_the_latest_goals_awaiting_a_response_only() -> None:
    """At a client, each record costs a bounded number of the machine's decisions: of the goals whose
    responses never came, the judge reads the server's states against the latest AWAITING_REFUSALS
    only.  A refusal of a goal it let go is judged on the state its response found: a FINISHED
    refused busy, its child heard to run and end between, is then R4.16."""
    from dynevent.conformance.judge.observer import AWAITING_REFUSALS, Checker
    from dynevent.conformance.judge.trace import read_trace

    finished = {"dynamic_event_seq": 1, "event_type": 3, "category": "", "description": "", "id": 0}
    trace = Trace()
    trace.rows[0] = {**trace.rows[0], "tap": "client"}
    trace.begin().status(1, 1, "standby", 5).add("goal", goal_uuid=uuid(1), goal=finished)
    for n in range(2, AWAITING_REFUSALS + 2):  # requests whose responses never came
        trace.add("goal", goal_uuid=uuid(n), goal={**finished, "dynamic_event_seq": 0})
    trace.next(900, 6).feedback(900, "underway", 6).status(1, 2, "underway", 6)
    trace.status(1, 1, "standby", 6).result(900, "succeeded", "completed", 6)
    trace.add("goal_response", goal_uuid=uuid(1), accepted=False, reason="busy")
    header, records = read_trace(trace.text().splitlines(keepends=True), "t.jsonl")
    checker = Checker(header)
    for record in records:
        checker.push(record)
        assert len(checker._observer.requests.refusable) <= AWAITING_REFUSALS
    assert [finding[1:] for finding in found(checker.finish())] == [("R4.16", "rejected_acceptable")]


def test_a_status_that_disagrees_with_the_state() -> None:
    trace = Trace().started().result(1, "succeeded", "completed", 6).status(1, 2, "completed", 6)
    assert found(trace.check()) == [(trace.line, "R2.2", "status_mismatch")]


def test_a_status_with_an_unknown_phase() -> None:
    trace = Trace().started().status(1, 7, "underway", 6)
    assert found(trace.check()) == [(trace.line, "R2.2", "status_phase")]


def test_a_cancel_answered_before_the_child_ended() -> None:
    trace = Trace().started().goal(2, event_type=2, id=6).result(2, "succeeded", "canceled", 6)
    assert found(trace.check()) == [(trace.line, "R9.3", "cancel_answered_early")]


def test_a_result_id_that_does_not_match() -> None:
    trace = Trace().started().result(1, "succeeded", "completed", 9)
    assert found(trace.check()) == [(trace.line, "R8.1", "result_id")]


def test_a_finished_answer_naming_another_event() -> None:
    trace = (
        Trace()
        .begin()
        .status(1, 1, "standby", 5)
        .goal(1, event_type=3)
        .result(1, "succeeded", "completed", 6)
    )
    assert found(trace.check()) == [(trace.line, "R11.1", "result_id")]


def test_an_early_end_answered_as_a_success() -> None:
    trace = Trace().started().result(1, "succeeded", "canceled", 6)
    assert found(trace.check()) == [(trace.line, "R8.2", "goal_status")]


def test_log_seq_going_backwards_or_repeating() -> None:
    trace = Trace().started().feedback(1, "underway", 6, logs=(4,))
    trace.feedback(1, "underway", 6, logs=(2,))
    backwards = trace.line
    trace.feedback(1, "underway", 6, logs=(2,))
    report = trace.check()
    assert found(report) == [(backwards, "R7.3", "log_seq"), (trace.line, "R7.3", "log_seq")]
    assert "goes backwards" in report.findings[0].message and "repeats" in report.findings[1].message


@pytest.mark.spec("R7.3")
def test_a_log_seq_that_skips_is_the_servers_at_its_tap_and_an_open_item_seen_apart() -> None:
    """A log seq that skips within a child: at the server's tap, which hears every feedback, the
    server's (``skips``, no label from a recording); at a client's tap a feedback lost on the way
    leaves the same gap (``skips_or_lost``, the open item ``feedback_lost``)."""
    for tap, detail, label in (("server", "skips", "?"), ("client", "skips_or_lost", "feedback_lost")):
        trace = Trace()
        trace.rows[0] = {**trace.rows[0], "tap": tap}
        trace.started().feedback(1, "underway", 6, logs=(4,)).feedback(1, "underway", 6, logs=(6,))
        (finding,) = trace.check().findings
        assert (finding.line, finding.rule, finding.code, finding.detail) == (
            trace.line,
            "R7.3",
            "log_seq",
            detail,
        )
        assert divergences.label(finding) == label
        assert (label in divergences.OPEN_ITEMS) == (tap == "client")


def test_log_seq_wraps() -> None:
    trace = (
        Trace().started().feedback(1, "underway", 6, logs=(2**32 - 1,)).feedback(1, "underway", 6, logs=(0,))
    )
    assert trace.check().clean


def test_a_clamp_without_its_warning() -> None:
    trace = Trace().begin().status(1, 1, "standby", 5).next(1, 6, stubborn_period=0.5)
    trace.feedback(1, "underway", 6)
    assert found(trace.check()) == [(trace.line, "R12.2", "clamp_not_reported")]
    trace.rows[-1]["feedback"]["logs"] = [{"seq": 0, "tier": "warning", "unix_millis_time": 0, "text": "2 s"}]
    assert trace.check().clean


def test_feedback_for_a_goal_not_running() -> None:
    trace = Trace().started().goal(2, event_type=2, id=6).feedback(2, "underway", 6)
    assert found(trace.check()) == [(trace.line, "R7.1", "feedback_not_running")]


def test_feedback_for_a_rejected_goal_says_so() -> None:
    trace = Trace().started().next(2, 7, accepted=False).feedback(2, "underway", 7)
    report = trace.check()
    assert found(report) == [(trace.line, "R7.1", "feedback_not_running")]
    assert report.findings[0].message.endswith(", rejected")


def test_feedback_for_a_goal_whose_response_was_not_heard_says_so() -> None:
    goal = {
        "dynamic_event_seq": 1,
        "event_type": 1,
        "category": "go_to_place",
        "description": '"pantry"',
        "id": 7,
    }
    trace = Trace().started().add("goal", goal_uuid=uuid(2), goal=goal)  # its response: not in the trace
    trace.feedback(2, "underway", 7)
    report = trace.check()
    assert found(report) == [(trace.line, "R7.1", "feedback_not_running")]
    assert report.findings[0].message.endswith(", no response to it heard")


def test_feedback_after_the_terminal_answer() -> None:
    trace = Trace().started().result(1, "succeeded", "completed", 6).feedback(1, "underway", 6)
    assert found(trace.check()) == [(trace.line, "R19.1", "after_answer")]


def test_feedback_naming_another_child() -> None:
    trace = Trace().started().feedback(1, "underway", 8)
    assert found(trace.check()) == [(trace.line, "R7.1", "feedback_id")]


def test_a_child_not_named_by_its_goal() -> None:
    trace = Trace().begin().status(1, 1, "standby", 5).next(1, 6).feedback(1, "underway", 9)
    first = trace.line
    trace.status(1, 2, "underway", 9)
    assert found(trace.check()) == [(first, "R6.2", "child_id")]


@pytest.mark.spec("R6.4", "R6.2", "R9.1")
def test_a_start_feedback_naming_another_child_than_the_status_does_is_the_feedbacks_fault() -> None:
    """The child's start feedback names id 9, the status that shows it running names 6, the NEXT's:
    the child has its NEXT's id and the feedback names the wrong one (R6.4), not a child numbered
    otherwise (R6.2).  The judge keeps id 6, so a CANCEL of child 6 stops it, with no finding."""
    trace = Trace().begin().status(1, 1, "standby", 5).next(1, 6).feedback(1, "underway", 9)
    first = trace.line
    trace.status(1, 2, "underway", 6).goal(2, event_type=2, id=6)
    trace.result(1, "aborted", "canceled", 6).result(2, "succeeded", "canceled", 6)
    trace.status(1, 1, "standby", 6)
    assert found(trace.check()) == [(first, "R6.4", "feedback_id")]


def test_a_goal_that_does_not_lose_its_race() -> None:
    trace = Trace().begin().status(1, 1, "standby", 5).next(1, 6).next(2, 7)
    trace.feedback(1, "underway", 6).status(1, 2, "underway", 6).feedback(2, "underway", 7)
    report = trace.check()
    assert found(report) == [(trace.line, "R5.2", "race_not_lost")]
    assert "event 6 holds the running slot" in report.findings[0].expected


def test_a_cancel_response_against_r10() -> None:
    trace = (
        Trace()
        .started()
        .add("cancel_request", goal_uuid=uuid(77))
        .add("cancel_response", goal_uuid=uuid(77), accepted=True)
    )
    assert found(trace.check()) == [(trace.line, "R10.5", "cancel_response")]


def test_an_action_level_cancel_is_followed() -> None:
    trace = Trace().started().add("cancel_response", goal_uuid=uuid(1), accepted=True)
    trace.result(1, "canceled", "canceled", 6).status(1, 1, "standby", 6)
    assert trace.check().clean


def test_a_begin_out_of_turn() -> None:
    trace = Trace().begin().status(1, 1, "standby", 5).begin(seq=2)
    active = trace.line
    trace.status(2, 1, "standby", 5).goal(1, event_type=3, dynamic_event_seq=2)
    trace.result(1, "succeeded", "completed", 5).status(2, 0, "uninitialized", 0).begin(seq=5)
    assert found(trace.check()) == [(active, "R3.4", "begin_while_active"), (trace.line, "R3.1", "begin_seq")]


def test_a_goal_uuid_reused_while_open() -> None:
    trace = Trace().started().next(1, 7)
    assert found(trace.check()) == [(trace.line - 1, "R18.2", "goal_uuid_reused")]


def test_a_trace_from_a_late_subscriber_binds_the_running_goal() -> None:
    trace = Trace(config=False).status(4, 2, "underway", 12).feedback(9, "delayed", 12)
    trace.result(9, "succeeded", "completed", 12).status(4, 1, "standby", 12)
    trace.goal(10, event_type=3, dynamic_event_seq=4).result(10, "succeeded", "completed", 3)
    assert trace.check().clean


def test_an_answer_a_step_owed_that_never_came_is_missing_at_that_step() -> None:
    """A CANCEL stops the child, whose NEXT is answered; the CANCEL's own answer never comes."""
    trace = Trace().started().goal(2, event_type=2, id=6).status(1, 1, "standby", 6)
    owed_at = trace.line
    trace.result(1, "aborted", "canceled", 6).next(3, 7).feedback(3, "underway", 7)
    assert found(trace.check()) == [(owed_at, "R19.1", "answer_missing")]
    assert "never answered" in trace.check().findings[0].message


# --------------------------------------------------------------------------- a tap at a client


def _client_view(rows: list[dict[str, Any]], moves: list[tuple[int, int]]) -> str:
    """The records as a client may see them: each ``(record, later)`` pair moves a record to just after
    the one ``later`` places on (channels in order each, not with one another)."""
    rows = list(rows)
    for index, later in moves:
        row = rows.pop(index)
        rows.insert(index + later, row)
    return "".join(_json.dumps(row) + "\n" for row in rows)


def _clean_run() -> Trace:
    """begin, a NEXT run to its end, a CANCEL of a second child, FINISHED: as the server wrote it."""
    trace = Trace().started().result(1, "succeeded", "completed", 6).status(1, 1, "standby", 6)
    trace.next(2, 7).feedback(2, "underway", 7).status(1, 2, "underway", 7)
    trace.goal(3, event_type=2, id=7)
    trace.result(2, "aborted", "canceled", 7).result(3, "succeeded", "canceled", 7).status(1, 1, "standby", 7)
    trace.goal(4, event_type=3).result(4, "succeeded", "completed", 5).status(1, 0, "uninitialized", 0)
    return trace


def _index(trace: Trace, kind: str, **match: Any) -> int:
    """The row index (the config record is 0) of the first record of ``kind`` with these fields."""
    for index, row in enumerate(trace.rows):
        if row["type"] == kind and all(row.get(key) == value for key, value in match.items()):
            return index
    raise AssertionError(f"no {kind} {match}")


@pytest.mark.spec("R19.1", "R2.2")
def test_a_trace_from_a_tap_at_a_client_is_read_in_the_servers_order() -> None:
    """A client sees each channel in order, not the channels in order with one another: a goal's
    feedback before its response, a start's status before the response, a child's end on the status
    topic before its answer, FINISHED's INACTIVE before its response; the observer reads all of that as
    the server's order, and the same trace is clean."""
    trace = _clean_run()
    assert trace.check().clean
    rows = trace.rows
    response_1 = _index(trace, "goal_response", goal_uuid=uuid(1))
    end_1 = _index(trace, "result", goal_uuid=uuid(1))
    response_2 = _index(trace, "goal_response", goal_uuid=uuid(2))
    answers_2 = _index(trace, "result", goal_uuid=uuid(2))
    response_4 = _index(trace, "goal_response", goal_uuid=uuid(4))
    moves = {
        "feedback before response": [(response_1, 1)],
        "status before response": [(response_2, 2)],
        "child end's status before its answers": [(answers_2, 2), (answers_2, 2)],
        "status before answer": [(end_1, 1)],
        "INACTIVE before FINISHED's response": [(response_4, 2)],
    }
    for name, move in moves.items():
        text = _client_view(rows, move)
        assert text != trace.text(), name
        report = check_trace(text, name)
        assert report.clean, (name, report.findings)


@pytest.mark.spec("R3.1", "R3.2")
def test_a_new_runs_status_may_be_read_before_its_begin() -> None:
    """The run after the wrap begins: its WAITING status, on the status topic, is read just before its
    begin; the observer reads the begin first.  A status of a run whose begin never comes is still
    flagged."""
    trace = Trace().begin(4294967295).status(4294967295, 1, "standby", 0)
    trace.goal(1, event_type=3, dynamic_event_seq=4294967295).result(1, "succeeded", "completed", 0)
    trace.status(4294967295, 0, "uninitialized", 0).begin(0).status(0, 1, "standby", 0)
    assert trace.check().clean
    rows = trace.rows
    begin = _index(trace, "begin", message=rows[-2]["message"])
    swapped = _client_view(rows, [(begin, 1)])
    assert swapped != trace.text()
    assert check_trace(swapped, "swapped").clean
    alone = Trace().begin(4294967295).status(4294967295, 1, "standby", 0)
    alone.goal(1, event_type=3, dynamic_event_seq=4294967295).result(1, "succeeded", "completed", 0)
    alone.status(4294967295, 0, "uninitialized", 0).status(0, 1, "standby", 0)
    assert [code for _, _, code in found(alone.check())] == ["status_mismatch"]


@pytest.mark.spec("R2.2", "R11.1")
def test_a_latched_begin_that_opens_a_trace_does_not_name_the_runs_id_through_a_later_status() -> None:
    """A tap that joins a run late reads the latched begin, then the latched status of a later step
    (another time): its id is the highest used, a child's, not the run's own, which the FINISHED's
    answer then tells.  The begin's own status (the same time) still names it."""

    def opened(status_time: int, event_id: int) -> Trace:
        trace = Trace(config=False)
        begin = {"fleet": "tinyRobot", "robot": "tinyRobot1", "dynamic_event_seq": 2, "description": "{}"}
        trace.add("begin", message={**begin, "start_time": {"sec": 100, "nanosec": 0}})
        trace.add("status", message={"dynamic_event_seq": 2, "dynamic_state": 1, "status": "standby",
                                     "id": event_id, "time": {"sec": status_time, "nanosec": 0}})  # fmt: skip
        return trace.goal(1, event_type=3, dynamic_event_seq=2).result(1, "succeeded", "completed", 1)

    assert opened(160, 2).check().clean
    assert [code for _, _, code in found(opened(100, 2).check())] == ["result_id"]


def test_a_late_subscriber_may_read_the_latched_begin_after_the_status() -> None:
    trace = Trace(config=False).status(1, 1, "standby", 5).begin()
    trace.next(1, 6).feedback(1, "underway", 6).status(1, 2, "underway", 6)
    assert trace.check().clean
    again = Trace(config=False).status(1, 1, "standby", 5).begin().begin()
    assert [code for _, _, code in found(again.check())] == ["begin_while_active", "begin_seq"]


def test_a_trace_writer_writes_what_check_reads(tmp_path: Path) -> None:
    from dynevent.conformance.judge.trace import TraceWriter, observation
    from dynevent.wire.messages import DynamicEventStatus

    writer = TraceWriter(str(tmp_path / "t.jsonl"), fleet="tinyRobot", robot="tinyRobot1")
    status = DynamicEventStatus(dynamic_event_seq=1, dynamic_state=1, status="standby", id=5)
    writer.write(observation("status", 100 * 10**9, message=status))
    writer.comment("case  one\nline")
    writer.write(
        observation(
            "goal", 100_500_000_000, goal_uuid=uuid(1), message=Goal(dynamic_event_seq=1, event_type=3)
        )
    )
    writer.write(observation("goal_response", 100_600_000_000, goal_uuid=uuid(1), accepted=False))
    writer.close()
    writer.write(observation("status", 101 * 10**9, message=status))  # after close: nothing, no error
    lines = (tmp_path / "t.jsonl").read_text("utf-8").splitlines()
    assert lines[0] == '{"type":"config","fleet":"tinyRobot","robot":"tinyRobot1"}'
    assert lines[2] == "# case one line"
    assert len(lines) == 5
    header, records = read_trace(lines, "t")
    assert (header.fleet, header.robot) == ("tinyRobot", "tinyRobot1")
    assert [(record.kind, record.time) for record in records] == [
        ("status", 100 * 10**9),
        ("goal", 100_500_000_000),
        ("goal_response", 100_600_000_000),
    ]
    report = check_trace("\n".join(lines), "t")
    assert [(finding.rule, finding.code) for finding in report.findings] == [("R4.16", "rejected_acceptable")]


# --------------------------------------------------------------------------- rmf_ros2 as it behaves today

#: Each rmf_ros2 defect of docs/divergences.md that a trace shows, and the findings that flag it.
RMF_ROS2_DEFECTS: dict[str, set[tuple[str, str]]] = {
    "D1": {("R4.6", "accepted_busy"), ("R5.2", "race_not_lost")},  # a CANCEL frees the robot early
    "D2": {("R2.2", "status_mismatch")},  # the status after a child's end says RUNNING
    "D5": {("R5.2", "race_not_lost")},  # the seq is not checked again at start
    "D7": {("R4.5", "accepted_unknown_event_type")},  # bad event types accepted, then aborted
    "D8": {("R4.14", "accepted_cancel_id_mismatch")},  # bad CANCELs accepted, then aborted
    "D9": {("R7.3", "log_seq")},  # LogEntry.seq is the dynamic event seq
    "D11": {("R12.2", "clamp_not_reported")},  # the stubborn clamp is silent
    "D12": {("R4.11", "accepted_non_finite_stubborn_period")},  # a NaN stubborn period is accepted
}
#: Defects no trace can show: interruptions, resumes, task signals and the adapter's shutdown are
#: task inputs, not on the wire (a NEXT deferred after an unseen resume looks the same as one deferred
#: by an unseen interruption); an answer that never comes (D15, D21) shows only as an absence a trace
#: cannot bound; a nested run (D22) needs a configuration no trace header may hold (R4.17); a holding
#: itinerary (D24) travels on the traffic schedule, not on the Dynamic Event topics.
NOT_ON_THE_WIRE = {"D3", "D4", "D14", "D15", "D21", "D22", "D23", "D24"}
#: Defects first seen on the deployed adapter, which the example trace predates: the lab's recordings
#: show them, and tests/conformance/judge/test_rmf_ros2_recordings.py holds check to what it finds
#: there (D26 as R2.2 at every begin; D27 is the adapter's crash, an absence; D29 a log line no rule
#: forbids a child to write; D30 and D31 are flagged in the probe's recording).
IN_THE_RECORDINGS = {"D26", "D27", "D29", "D30", "D31"}


def _rmf_ros2() -> Report:
    return check_trace((EXAMPLES / "rmf_ros2-trace.jsonl").read_text(encoding="utf-8"), "rmf_ros2")


def test_the_rmf_ros2_trace_is_flagged_for_each_defect() -> None:
    report = _rmf_ros2()
    kinds = {(finding.rule, finding.code) for finding in report.findings}
    assert kinds == set().union(*RMF_ROS2_DEFECTS.values())
    seq_recheck = [finding for finding in report.findings if "no longer the run's seq" in finding.expected]
    busy_start = [finding for finding in report.findings if "holds the running slot" in finding.expected]
    assert len(seq_recheck) == len(busy_start) == 1


def test_every_defect_divergences_lists_is_flagged() -> None:
    """docs/divergences.md lists rmf_ros2's defects; the rmf_ros2 trace shows each one a wire can show."""
    path = ROOT / "docs" / "divergences.md"
    if not path.exists():
        pytest.skip("docs/divergences.md is not written yet")
    rows = re.findall(
        r"^\| (D\d+) \| (.+?) \| (defect|decision) \|", path.read_text(encoding="utf-8"), re.MULTILINE
    )
    defects = {name for name, _, kind in rows if kind == "defect"}
    assert defects, "no defect found in the table of docs/divergences.md"
    unclassified = defects - set(RMF_ROS2_DEFECTS) - NOT_ON_THE_WIRE - IN_THE_RECORDINGS
    assert not unclassified, f"defects of docs/divergences.md this test does not know: {sorted(unclassified)}"
    kinds = {(finding.rule, finding.code) for finding in _rmf_ros2().findings}
    for name in sorted(defects - NOT_ON_THE_WIRE - IN_THE_RECORDINGS):
        assert RMF_ROS2_DEFECTS[name] <= kinds, name


# --------------------------------------------------------------------------- unreadable input


@pytest.mark.parametrize(
    ("line", "field"),
    [
        ("[1, 2]", "$"),
        ('{"type": "nothing", "time": 1}', "type"),
        ('{"type": "status", "time": 1}', "message"),
        ('{"type": "status", "time": 1, "message": {}, "extra": 1}', "extra"),
        ('{"type": "status", "time": "noon", "message": {}}', "time"),
        ('{"type": "status", "time": 1e300, "message": {}}', "time"),
        ('{"type": "status", "time": 1, "message": {"dynamic_state": 300}}', "message.dynamic_state"),
        ('{"type": "goal", "time": 1, "goal_uuid": "xyz", "goal": {}}', "goal_uuid"),
        ('{"type": "goal", "time": 1, "goal_uuid": "' + "0" * 32 + '", "goal": {"id": -1}}', "goal.id"),
        (
            '{"type": "goal_response", "time": 1, "goal_uuid": "' + "0" * 32 + '", "accepted": true}',
            "goal_uuid",
        ),
        ('{"type": "goal_response", "time": 1, "goal_uuid": "' + "0" * 32 + '", "accepted": 1}', "accepted"),
        (
            '{"type": "result", "time": 1, "goal_uuid": "' + "0" * 32 + '", "status": "won", "result": {}}',
            "status",
        ),
        (
            '{"type": "feedback", "time": 1, "goal_uuid": "'
            + "0" * 32
            + '", "feedback": {"logs": [{"seq": "a"}]}}',
            "feedback.logs[0].seq",
        ),
        (
            '{"type": "config", "config": {"categories": {"a": {"accept": "nothing"}}}}',
            "config.categories.a.accept",
        ),
        (
            '{"type": "cancel_response", "time": 1, "goal_uuid": "'
            + "0" * 32
            + '", "accepted": false, "terminated": "yes"}',
            "terminated",
        ),
        (
            '{"type": "cancel_response", "time": 1, "goal_uuid": "'
            + "0" * 32
            + '", "accepted": true, "terminated": true}',
            "terminated",
        ),
    ],
)
def test_unreadable_input_names_the_line_and_the_field(line: str, field: str) -> None:
    text = "# a comment\n\n" + line + "\n"
    with pytest.raises(TraceError) as caught:
        check_trace(text, "bad.jsonl")
    assert (caught.value.source, caught.value.line, caught.value.field) == ("bad.jsonl", 3, field)
    assert str(caught.value).startswith(f"bad.jsonl:3: {field}: ")


def test_a_config_record_comes_first() -> None:
    text = _json.dumps({"type": "status", "time": 1, "message": {}}) + "\n" + _json.dumps(CONFIG) + "\n"
    with pytest.raises(TraceError, match=r"<trace>:2: type: a 'config' record"):
        check_trace(text)


def test_a_trace_says_where_it_was_seen() -> None:
    """The config record's ``tap``: ``client`` (channels that may lag one another) or ``server``."""
    for tap in TAPS:
        header, _ = read_trace([_json.dumps({"type": "config", "tap": tap})])
        assert header.tap == tap
    header, _ = read_trace([_json.dumps({"type": "config"})])
    assert header.tap is None
    refusal = r"<trace>:1: tap: expected one of \['client', 'server'\], got \"robot\""
    with pytest.raises(TraceError, match=refusal):
        check_trace(_json.dumps({"type": "config", "tap": "robot"}) + "\n")
    writer = TraceWriter(None, fleet="f", robot="r", tap="client")
    assert read_trace(writer.text().splitlines())[0].tap == "client"


#: What a probe heard of a FINISHED on a loaded machine: the robot's status, then its run's begin read
#: latched, then the FINISHED, its response, the run's INACTIVE status and, last, its answer.
_FINISHED_AT_A_CLIENT = [
    {"type": "config", "fleet": "tinyRobot", "robot": "r1", "tap": "client"},
    {"type": "status", "time": 8.49, "message": {"dynamic_event_seq": 4294967295, "dynamic_state": 1,
                                                  "status": "standby", "id": 1, "time": {"sec": 1}}},
    {"type": "begin", "time": 8.491, "message": {"fleet": "tinyRobot", "robot": "r1",
                                                  "dynamic_event_seq": 4294967295, "description": "{}",
                                                  "start_time": {"sec": 1}}},
    {"type": "goal", "time": 8.495, "goal_uuid": "d" * 32, "goal": {"dynamic_event_seq": 4294967295,
                                                                      "event_type": 3}},
    {"type": "goal_response", "time": 8.497, "goal_uuid": "d" * 32, "accepted": True},
    {"type": "status", "time": 8.504, "message": {"dynamic_event_seq": 4294967295, "dynamic_state": 0,
                                                   "status": "uninitialized", "id": 0, "time": {"sec": 8}}},
    {"type": "result", "time": 8.505, "goal_uuid": "d" * 32, "status": "succeeded",
     "result": {"status": "completed", "id": 1}},
]  # fmt: skip


@pytest.mark.spec("R2.3", "R3.4", "R11.1")
def test_a_client_reads_a_finished_s_answer_after_the_inactive_status_of_its_step() -> None:
    """At a client the run's INACTIVE status may come before the answer of the FINISHED that ended it
    (R2.3 orders them the other way at the server), and the latched begin of the run the trace starts
    in after its status: neither is a finding.  (The latched begin is the current run's, not a next
    run's whose predecessor's INACTIVE status would go before it: read so, it once ended the run
    before the FINISHED was accepted.)"""
    lines = [_json.dumps(row) for row in _FINISHED_AT_A_CLIENT]
    assert check_trace(lines).findings == ()


def test_read_trace_skips_comments_and_parses_times_in_seconds() -> None:
    header, records = read_trace(["# hi", "", '{"type": "status", "time": 1.5, "message": {}}'])
    assert header.config is None and len(records) == 1
    assert (records[0].line, records[0].time) == (3, 1_500_000_000)


_VALID = Trace().started().result(1, "succeeded", "completed", 6).rows


@given(st.lists(st.text(max_size=80) | st.sampled_from([_json.dumps(row) for row in _VALID]), max_size=12))
def test_arbitrary_lines_give_findings_or_the_trace_error(lines: list[str]) -> None:
    try:
        report = check_trace(lines, "fuzz")
    except TraceError as exc:
        assert exc.line >= 1
    else:
        assert report.records <= len(lines)


_FIELD_VALUES = st.one_of(
    st.integers(-5, 2**64), st.text(max_size=8), st.booleans(), st.none(), st.floats(allow_nan=False)
)


@given(st.lists(st.tuples(st.integers(0, len(_VALID) - 1), st.text(max_size=12), _FIELD_VALUES), max_size=8))
def test_mutated_records_give_findings_or_the_trace_error(mutations: list[tuple[int, str, Any]]) -> None:
    rows = [dict(row) for row in _VALID]
    for index, key, value in mutations:
        target = rows[index]
        # a nested object still an object (an earlier mutation may have replaced it with a value)
        objects = ("message", "goal", "feedback", "result")
        nested = [name for name in objects if isinstance(target.get(name), dict)]
        if nested and key:
            target[nested[0]] = {**target[nested[0]], key: value}
        else:
            target[key or "time"] = value
    with contextlib.suppress(TraceError):
        check_trace([_json.dumps(row) for row in rows], "fuzz")


def test_check_reads_a_trace_as_a_stream_holding_a_few_records(monkeypatch: pytest.MonkeyPatch) -> None:
    """Memory stays flat: the observer never has more than LOOKAHEAD records read ahead of it."""
    import sys
    from pathlib import Path

    from dynevent.conformance.judge import observer

    root = str(Path(__file__).resolve().parents[3])
    if root not in sys.path:
        sys.path.insert(0, root)
    from bench.traces import cycle_lines

    produced = 0
    ahead: list[int] = []

    def lines() -> Any:
        nonlocal produced
        for line in cycle_lines(300):
            produced += 1
            yield line

    feed = observer._Observer.feed

    def counting_feed(self: Any, record: Any) -> None:
        ahead.append(produced - record.line)
        feed(self, record)

    monkeypatch.setattr(observer._Observer, "feed", counting_feed)
    report = check_trace(lines(), "long")
    assert report.clean and report.records == len(ahead) == 2102
    assert max(ahead) == observer.LOOKAHEAD


def test_a_size_limit_refusal_before_the_json_check_is_legal_without_a_config() -> None:
    """R4.8 runs before R4.9: a server with a small description limit refuses a NEXT whose description
    is not JSON as ``description_invalid``.  Without a config record, check cannot rule that limit
    out, so the refusal is no finding (it once was an ``R4.9 wrong_reason``: the order of the checks
    was rebuilt from the declaration order of the reasons instead of asked of the machine)."""
    trace = Trace(config=False).begin().status(1, 1, "standby", 5)
    trace.next(1, 6, accepted=False, reason="description_invalid", description="not json")
    assert found(trace.check()) == []


def test_a_refusal_the_configuration_cannot_explain_is_still_found_without_a_config() -> None:
    """A NEXT with a JSON description refused ``description_not_json``: no configuration gives that."""
    trace = Trace(config=False).begin().status(1, 1, "standby", 5)
    trace.next(1, 6, accepted=False, reason="description_not_json")
    assert found(trace.check()) == [(trace.line, "R4.16", "rejected_acceptable")]


def _rmf_ros2_session() -> str:
    """A run as serve's rmf_ros2 mode carries it out (the adapter numbers children; the status stays
    RUNNING with the child's final status), written as a trace without a config record."""
    config = machine.ServerConfig.rmf_ros2({"go_to_place": machine.any_description})
    state = machine.State.new("tinyRobot", "tinyRobot1")
    rows: list[dict[str, Any]] = []
    now = 10**9
    events: list[ins.Input] = [ins.Begin(description="{}", event_id=1, now=now)]
    for number, goal_id in enumerate((7, 9), start=1):  # the ids are ignored (D10)
        goal = Goal(dynamic_event_seq=1, event_type=1, category="go_to_place", description='"p"', id=goal_id)
        events += [
            ins.GoalRequested(goal_uuid=uuid(number), goal=goal, now=now),
            ins.GoalStarted(goal_uuid=uuid(number), now=now),
            ins.ChildFinished(status="completed", now=now),
        ]
    for planned in events:
        now += 10**8
        event = attrs.evolve(planned, now=now)
        transition = machine.step(state, event, config)
        state = transition.state
        rows.extend(step_records(event, transition.outputs))
    return "".join(_json.dumps(row) + "\n" for row in rows)


@pytest.mark.spec("R17.4", "R6.2")
def test_check_judges_a_server_as_serve_s_rmf_ros2_mode_when_asked() -> None:
    """What serve's rmf_ros2 mode does is a finding against the spec, and none with
    ``compatibility="rmf_ros2"`` (which a trace's config record overrides)."""
    text = _rmf_ros2_session()
    standard = {finding.code for finding in check_trace(text, "t").findings}
    assert "child_id" in standard, standard  # the adapter's own numbering, against the NEXT's id
    assert check_trace(text, "t", compatibility="rmf_ros2").clean
    with_config = _json.dumps(CONFIG) + "\n" + text  # a config record says standard: it wins
    assert not check_trace(with_config, "t", compatibility="rmf_ros2").clean


def _judged(judge: Any, records: list[Any]) -> Report:
    from dynevent.conformance.judge import Judge

    typed: Judge = judge  # mypy holds both judges to the one interface
    for record in records:
        typed.push(record)
    return typed.finish()


def test_both_judges_keep_the_one_interface() -> None:
    """The observer and the partial judge take records one at a time and give a report: the observer
    pushed by hand finds what check_trace finds, and the partial judge, from the topics alone, the
    status that shows a child id lower than the run showed before (R6.2)."""
    from dynevent.conformance.judge import Checker, PartialJudge

    trace = Trace().started().result(1, "succeeded", "completed", 6).status(1, 2, "completed", 6)
    header, records = read_trace(trace.text().splitlines(), "t")
    assert found(_judged(Checker(header), records)) == found(trace.check()) != []
    topics = Trace().begin().status(1, 1, "standby", 0)
    topics.status(1, 2, "underway", 5).status(1, 2, "underway", 4)
    header, records = read_trace(topics.text().splitlines(), "t")
    assert found(_judged(PartialJudge(header, margin=10**9), records)) == [(topics.line, "R6.2", "status_id")]


def _latched(seq: int, state: int, status: str, event_id: int) -> str:
    return (
        f'{{"time":1,"type":"status","message":{{"dynamic_event_seq":{seq},"dynamic_state":{state},'
        f'"status":"{status}","id":{event_id},"time":{{"sec":1,"nanosec":0}}}}}}\n'
        f'{{"time":1,"type":"begin","message":{{"fleet":"f","robot":"r","dynamic_event_seq":{seq},'
        f'"description":"{{}}","start_time":{{"sec":0,"nanosec":0}}}}}}\n'
    )


@pytest.mark.spec("R3.1")
def test_the_latched_begin_of_an_ended_run_read_after_its_status_is_no_new_run() -> None:
    """A late subscriber reads the two latched topics in either order: the INACTIVE status of run 5,
    then run 5's begin, is that run's, not a begin of run 5 again (the probe joins such servers)."""
    after = (
        '{"time":2,"type":"begin","message":{"fleet":"f","robot":"r","dynamic_event_seq":6,'
        '"description":"{}","start_time":{"sec":2,"nanosec":0}}}\n'
    )
    assert check_trace(_latched(5, 0, "uninitialized", 0) + after).clean
    assert check_trace(_latched(5, 1, "standby", 3)).clean
    skipped = after.replace('"dynamic_event_seq":6', '"dynamic_event_seq":7')
    report = check_trace(_latched(5, 0, "uninitialized", 0) + skipped)
    assert [(finding.rule, finding.code) for finding in report.findings] == [("R3.1", "begin_seq")]


# --------------------------------------------------------------------------- a trace heard out to its end


@pytest.mark.spec("R19.1")
def test_a_request_never_responded_to_is_missing_only_where_the_trace_says_it_heard_the_server_out() -> None:
    """An ``end`` record (the tap heard the server out: the probe writes it over a link that lost
    nothing) makes what the trace lacks by then the judge's: a goal request with no response, at its
    request's line.  Without it the trace may have stopped while the response was on its way."""
    trace = Trace().begin().status(1, 1, "standby", 5).add("goal", goal_uuid=uuid(1), goal={
        "dynamic_event_seq": 1, "event_type": 3})  # fmt: skip
    asked = trace.line
    assert trace.check().clean
    trace.add("end")
    assert found(trace.check()) == [(asked, "R19.1", "response_missing")]
    finding = trace.check().findings[0]
    assert uuid(1) in finding.message and finding.expected == "a response, accepted or rejected (R19.1)"
    # a clean trace heard out stays clean: every response and answer came
    whole = Trace().started().result(1, "succeeded", "completed", 6).status(1, 1, "standby", 6).add("end")
    assert whole.check().clean, found(whole.check())


@pytest.mark.spec("R19.1", "R5.1", "R11.1")
def test_a_goal_accepted_and_never_started_by_the_trace_s_end_owes_what_its_start_owes() -> None:
    """A FINISHED accepted and never answered: a client's tap does not see a goal start, so the trace
    could end before it; heard out, the server had started it (the transport starts a goal it
    accepted), and the answer its start owes is missing.  A CANCEL of the running child owes nothing
    at its start, and a NEXT whose child still runs nothing yet: a child's end is the robot's."""
    finished = Trace().begin().status(1, 1, "standby", 5).goal(1, event_type=3)
    accepted = finished.line - 1
    assert finished.check().clean
    assert found(finished.add("end").check()) == [(accepted, "R19.1", "answer_missing")]
    running = Trace().started().goal(2, event_type=2, id=6).add("end")
    assert running.check().clean, found(running.check())


@pytest.mark.spec("R19.1", "R10.3")
def test_an_action_level_cancel_never_responded_to_is_missing_where_the_trace_heard_the_server_out() -> None:
    trace = Trace().started().add("cancel_request", goal_uuid=uuid(1))
    asked = trace.line
    assert trace.check().clean
    assert found(trace.add("end").check()) == [(asked, "R19.1", "response_missing")]


def test_a_record_after_the_end_record_is_unreadable() -> None:
    trace = Trace().started().add("end")
    end = trace.line
    trace.status(1, 2, "underway", 6)
    with pytest.raises(
        TraceError, match=rf"t\.jsonl:{end + 1}: type: a record after the trace's end \(line {end}\)"
    ):
        trace.check()
