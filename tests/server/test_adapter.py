"""The fleet adapter's side of a server, without ROS: the adapter's inputs on a clock, its children
run through their handles, and stubbornness carried out on its holds."""

from __future__ import annotations

from typing import Any

import pytest

from dynevent.server import inputs as ins
from dynevent.server import outputs as outs
from dynevent.server.adapter import AdapterInputs, ChildExecution, RunningChildren, carry_out_stubbornness
from dynevent.server.config import ServerConfig
from dynevent.server.holder import RobotServer
from dynevent.wire.messages import Goal
from dynevent.wire.vocab import EventType

SECOND = 10**9


class Children:
    """A ChildEvents that remembers what it was told."""

    def __init__(self) -> None:
        self.told: list[tuple[str, ChildExecution]] = []

    def start(self, execution: ChildExecution) -> None:
        self.told.append(("start", execution))

    def cancel(self, execution: ChildExecution) -> None:
        self.told.append(("cancel", execution))

    def kill(self, execution: ChildExecution) -> None:
        self.told.append(("kill", execution))

    def interrupt(self, execution: ChildExecution) -> None:
        self.told.append(("interrupt", execution))

    def resume(self, execution: ChildExecution) -> None:
        self.told.append(("resume", execution))


class Adapter(AdapterInputs):
    """A server on a clock that moves a second a step, its child outputs carried out at once."""

    def __init__(self) -> None:
        self.server = RobotServer("tinyRobot", "r1", ServerConfig(categories={"go": lambda *_: []}))
        self.clock = SECOND
        self.children = Children()
        self.running = RunningChildren(self, self.children, self.now)
        self.outputs: list[outs.Output] = []

    def now(self) -> int:
        self.clock += SECOND
        return self.clock

    def step(self, event: ins.Input) -> tuple[outs.Output, ...]:
        outputs = self.server.step(event)
        self.outputs.extend(outputs)
        for output in outputs:
            self.running.carry_out(output)
        return outputs


@pytest.mark.spec("R3.1", "R9.3", "R14.1")
def test_the_adapters_inputs_and_a_child_run_through_its_handle() -> None:
    adapter = Adapter()
    adapter.begin("{}", 1)
    assert adapter.server.state.active
    goal = Goal(
        dynamic_event_seq=adapter.server.state.seq,
        event_type=EventType.NEXT,
        category="go",
        description='"x"',
        id=2,
    )
    adapter.step(ins.GoalSubmitted(goal_uuid="ab" * 16, goal=goal, now=adapter.now()))
    ((told, execution),) = adapter.children.told
    assert told == "start" and execution.id == 2 and execution.category == "go" and execution.okay()
    execution.underway("moving")
    assert any(isinstance(output, outs.PublishFeedback) for output in adapter.outputs)
    adapter.interrupt()
    adapter.resume()
    cancel = Goal(dynamic_event_seq=goal.dynamic_event_seq, event_type=EventType.CANCEL, id=2)
    adapter.step(ins.GoalSubmitted(goal_uuid="cd" * 16, goal=cancel, now=adapter.now()))
    assert [name for name, _ in adapter.children.told] == ["start", "interrupt", "resume", "cancel"]
    assert execution.stopping == "canceled" and not execution.okay() and not execution.done
    execution.finished()  # the stop's status: the child ended canceled
    assert execution.done and "finished" in repr(execution)
    answers = [output for output in adapter.outputs if isinstance(output, outs.AnswerGoal)]
    assert [answer.result.status for answer in answers] == ["canceled", "canceled"]
    before = len(adapter.outputs)
    execution.error("too late")  # after the end: nothing
    assert len(adapter.outputs) == before
    adapter.shutdown()
    assert adapter.server.state.shutdown


class Holds:
    def __init__(self) -> None:
        self.told: list[tuple[Any, ...]] = []

    def begin(self, period: float, map_name: str | None, x: float, y: float) -> None:
        self.told.append(("begin", period, map_name, x, y))

    def hold(self, period: float, map_name: str, x: float, y: float) -> None:
        self.told.append(("hold", period, map_name, x, y))

    def delay(self, seconds: float) -> None:
        self.told.append(("delay", seconds))

    def end(self) -> None:
        self.told.append(("end",))


def test_stubbornness_is_carried_out_on_the_holds_and_nothing_else_is() -> None:
    holds = Holds()
    said = [
        outs.StubbornBegin(period=5.0, since=0, map_name="L1", x=1.0, y=2.0),
        outs.StubbornHold(period=4.0, since=0, map_name="L1", x=3.0, y=2.0),
        outs.StubbornDelay(delay=1.5),
        outs.StubbornEnd(),
    ]
    assert all(carry_out_stubbornness(holds, output) for output in said)
    assert holds.told == [
        ("begin", 5.0, "L1", 1.0, 2.0),
        ("hold", 4.0, "L1", 3.0, 2.0),
        ("delay", 1.5),
        ("end",),
    ]
    assert all(carry_out_stubbornness(None, output) for output in said)  # no holds: carried out as nothing
    assert not carry_out_stubbornness(holds, outs.CancelChild(id=1))
