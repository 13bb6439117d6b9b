"""Judging clients (docs/spec.md section 22): each rule caught on the goal that breaks it, nothing
found where a client could not have known better, and the client machine judged clean."""

from __future__ import annotations

import random

import pytest

from dynevent import client as cl
from dynevent.conformance.judge.clients import ONE_CLIENT, ClientJudge
from dynevent.server import inputs as ins
from dynevent.server import machine
from dynevent.server import outputs as outs
from dynevent.server.machine import ServerConfig, State
from dynevent.tools.demo.simulated_session import Adapter, ChildScript, Options, SimulatedSession
from dynevent.wire._fields import SECOND
from dynevent.wire.messages import Goal
from dynevent.wire.vocab import ClientViolation, EventType

CONFIG = ServerConfig(categories={"go_to_place": machine.any_description})


@pytest.fixture(autouse=True, params=["requested", "submitted"])
def _binding(request: pytest.FixtureRequest, monkeypatch: pytest.MonkeyPatch) -> None:
    """Every judgement holds whether the server steps goal requests and starts (an in-process binding)
    or submits the goals its transport accepted (rclpy, R5.3)."""
    monkeypatch.setattr(Robot, "submit", request.param == "submitted")


class Robot:
    """A server machine and the judge that follows it; time in seconds."""

    submit = False

    def __init__(self, grace: float = 0.5) -> None:
        self.state = State.new("tinyRobot", "r1")
        self.judge = ClientJudge("tinyRobot", "r1", grace=grace, config=CONFIG)
        self.now = 10 * SECOND
        self.count = 0
        self.input(ins.Begin(description="{}", event_id=5, now=self.now))

    def at(self, seconds: float) -> Robot:
        self.now += round(seconds * SECOND)
        return self

    def input(self, event: ins.Input) -> None:
        transition = machine.step(self.state, event, CONFIG)
        self.state = transition.state
        self.judge.step(event, transition.outputs)

    def send(
        self, client: str, event_type: int, goal_id: int = 0, seq: int | None = None, **fields: object
    ) -> list[str]:
        """Send a goal now: judged as it arrives, then stepped (accepted goals start at once)."""
        self.count += 1
        uuid = f"{self.count:032x}"
        if event_type == EventType.NEXT:
            fields = {"category": "go_to_place", "description": '"pantry"', **fields}
        goal = Goal(
            dynamic_event_seq=self.state.seq if seq is None else seq,
            event_type=event_type,
            id=goal_id,
            **fields,
        )  # type: ignore[arg-type]
        found = self.judge.goal(client, uuid, goal, self.now)
        if self.submit:  # as an rclpy binding steps an accepted goal (R5.3); a refusal is not stepped
            if isinstance(machine.accept(self.state, goal, CONFIG), outs.Accepted):
                self.input(ins.GoalSubmitted(goal_uuid=uuid, goal=goal, now=self.now))
        else:
            self.input(ins.GoalRequested(goal_uuid=uuid, goal=goal, now=self.now))
            if any(queued.goal_uuid == uuid for queued in self.state.queued):
                self.input(ins.GoalStarted(goal_uuid=uuid, now=self.now))
        return [finding.violation.code for finding in found]

    def child_ends(self) -> None:
        self.input(ins.ChildFinished(status="completed", now=self.now))

    def close(self) -> list[str]:
        return [finding.violation.code for finding in self.judge.close(self.now)]


@pytest.mark.spec("R22.2", "R22.3", "R22.4", "R22.5", "R22.6", "R22.8")
def test_a_run_driven_well_is_judged_clean() -> None:
    robot = Robot()
    assert robot.at(1).send("a", EventType.NEXT, 6) == []
    robot.at(2).child_ends()
    assert robot.at(1).send("a", EventType.NEXT, 7) == []
    assert robot.at(1).send("a", EventType.CANCEL, 7) == []
    robot.child_ends()
    assert robot.at(1).send("a", EventType.NEXT, 0) == []  # id 0: the server names it
    robot.at(1).child_ends()
    assert robot.at(1).send("a", EventType.FINISHED) == []
    assert robot.close() == []
    assert robot.judge.findings == []


@pytest.mark.spec("R22.2")
def test_a_stale_seq_after_a_new_begin() -> None:
    robot = Robot()
    robot.at(1).send("a", EventType.FINISHED)
    robot.at(1).input(ins.Begin(description="{}", event_id=9, now=robot.now))
    assert robot.at(0.2).send("b", EventType.NEXT, 10, seq=1) == []  # within the grace period
    assert robot.at(1).send("b", EventType.NEXT, 10, seq=1) == ["stale_seq"]
    assert robot.send("a", EventType.NEXT, 10, seq=1) == ["stale_seq"]
    assert robot.send("b", EventType.NEXT, 10, seq=2) == []


@pytest.mark.spec("R22.3")
def test_goals_after_finished() -> None:
    robot = Robot()
    robot.at(1).send("a", EventType.FINISHED)
    assert robot.at(0.1).send("b", EventType.NEXT, 6) == []  # b may not have read the INACTIVE status
    assert robot.send("a", EventType.NEXT, 6) == ["after_finished"]  # a had its FINISHED answered
    assert robot.at(1).send("b", EventType.NEXT, 6) == ["after_finished"]


@pytest.mark.spec("R22.4")
def test_a_next_while_running() -> None:
    robot = Robot()
    robot.at(1).send("a", EventType.NEXT, 6)
    assert robot.at(0.1).send("a", EventType.NEXT, 7) == ["next_while_running"]  # its own NEXT is open
    assert robot.send("b", EventType.NEXT, 7) == []  # b could not know yet
    assert robot.at(1).send("b", EventType.FINISHED) == ["next_while_running"]
    robot.child_ends()
    assert robot.at(1).send("b", EventType.NEXT, 7) == []


@pytest.mark.spec("R22.5")
def test_a_cancel_naming_another_id_or_nothing() -> None:
    robot = Robot()
    assert robot.at(1).send("a", EventType.CANCEL, 5) == ["cancel_not_running"]
    robot.send("a", EventType.NEXT, 6)
    assert robot.at(1).send("a", EventType.CANCEL, 9) == ["cancel_not_running"]
    assert robot.send("a", EventType.CANCEL, 6) == []


@pytest.mark.spec("R22.6")
def test_a_stale_id() -> None:
    robot = Robot()
    robot.at(1).send("a", EventType.NEXT, 6)
    robot.at(1).child_ends()
    assert robot.at(1).send("a", EventType.NEXT, 6) == ["stale_id"]
    assert robot.send("a", EventType.NEXT, 7) == []


@pytest.mark.spec("R22.7")
@pytest.mark.parametrize(
    "goal",
    [
        {"event_type": 0},
        {"event_type": 4},
        {"event_type": EventType.NEXT, "goal_id": 6, "description": "{not json"},
        {"event_type": EventType.NEXT, "goal_id": 6, "stubborn_period": float("nan")},
    ],
)
def test_a_goal_no_server_accepts(goal: dict[str, object]) -> None:
    robot = Robot()
    assert robot.at(1).send("a", **goal) == ["never_acceptable"]  # type: ignore[arg-type]
    assert "no server accepts it" in robot.judge.findings[0].knew


@pytest.mark.spec("R22.8")
def test_a_run_left_open_is_the_last_driver_s() -> None:
    robot = Robot()
    robot.at(1).send("a", EventType.NEXT, 6)
    robot.at(1).child_ends()
    robot.at(1).send("b", EventType.NEXT, 7)
    robot.at(1).child_ends()
    assert robot.close() == ["run_left_open"]
    assert robot.judge.findings[-1].client == "b"
    quiet = Robot()  # a run no client drove is nobody's
    assert quiet.at(5).close() == []
    cancelled = Robot()
    cancelled.at(1).send("a", EventType.NEXT, 6)
    cancelled.input(ins.TaskCancel(now=cancelled.now))
    assert cancelled.close() == []


@pytest.mark.spec("R22.1")
def test_clients_are_told_apart_by_name_and_one_name_makes_one_client() -> None:
    """Two action clients (two names) each know only their own goals; a server that cannot tell
    clients apart judges every goal as one client's, so one client's open NEXT counts for the other."""
    apart = Robot()
    apart.at(1).send("gid-1", EventType.NEXT, 6)
    assert apart.at(0.1).send("gid-2", EventType.NEXT, 7) == []
    together = Robot()
    together.at(1).send(ONE_CLIENT, EventType.NEXT, 6)
    assert together.at(0.1).send(ONE_CLIENT, EventType.NEXT, 7) == ["next_while_running"]


def test_a_finding_reads_as_one_line() -> None:
    robot = Robot()
    robot.at(1).send(ONE_CLIENT, EventType.CANCEL, 5)
    line = robot.judge.findings[0].line()
    assert line.startswith("a client: R22.5 cancel_not_running: CANCEL seq=1 id=5 (the status was WAITING")
    assert line.endswith(f"expected {ClientViolation.CANCEL_NOT_RUNNING.instead}")


def test_the_grace_period_is_checked() -> None:
    for bad in (-1, float("nan"), float("inf"), True, "1"):
        with pytest.raises(ValueError, match="grace"):
            ClientJudge("f", "r", grace=bad)  # type: ignore[arg-type]


@pytest.mark.spec("R22.2", "R22.4", "R22.5", "R22.6")
@pytest.mark.parametrize("seed", range(40))
def test_the_client_machine_never_breaks_a_client_rule(seed: int) -> None:
    """Random sessions of the client machine against the server machine, over a simulated network
    whose messages take up to 0.2 s (under the grace period): the judge finds nothing."""
    rng = random.Random(seed)
    judge = ClientJudge("tinyRobot", "r1", grace=0.5, config=CONFIG)
    server = machine.step(
        State.new("tinyRobot", "r1"), ins.Begin(description="{}", event_id=5, now=SECOND), CONFIG
    ).state
    session = SimulatedSession(
        cl.ClientState.new(f"{seed:016x}"), server, CONFIG,
        adapter=Adapter(default=ChildScript(finish_after=rng.uniform(0.1, 2))),
        options=Options(delay=(0, 0.2)), seed=seed, now=SECOND,
    )  # fmt: skip
    original = session._server_step

    def server_step(event: ins.Input, direction: str, summary: str) -> tuple[object, ...]:
        if isinstance(event, ins.GoalRequested):
            judge.goal("client", event.goal_uuid, event.goal, event.now)
        outputs = original(event, direction, summary)
        judge.step(event, outputs)  # type: ignore[arg-type]
        return outputs

    session._server_step = server_step  # type: ignore[method-assign]
    judged = 0
    for _ in range(40):
        if not session.server.active:
            session.begin()
        command = rng.choice(["next", "next", "next", "cancel", "cancel", "withdraw", "wait", "finish"])
        if command == "next":
            session.request_next("go_to_place", '"pantry"')
        elif command == "withdraw":
            for goal in session.client.goals:
                session.request_withdraw(goal.goal_uuid)
        elif command == "cancel":
            session.request_cancel()
        elif command == "finish":
            session.request_finish()
        session.advance(rng.uniform(0, 1.5))
        judged = sum(1 for event in session.timeline if event.kind == "goal_requested")
    assert judged >= 8
    assert judge.findings == [], [finding.line() for finding in judge.findings]
    # the same judge catches a goal the client machine would never send
    stale = Goal(dynamic_event_seq=(session.server.seq - 1) % 2**32, event_type=EventType.FINISHED)
    assert [found.violation for found in judge.goal("other", "f" * 32, stale, session.now + SECOND)] == [
        ClientViolation.STALE_SEQ
    ]
