"""A client written for the deployed protocol works against standard mode (R20.1), and related rules.

``OneShotClient`` drives a robot the way the only public client does: one goal
per process, built from the FIRST status message it receives and nothing
else (seq = status.dynamic_event_seq; NEXT id = status.id + 1; CANCEL id =
status.id; FINISHED id 0).  It keeps no memory between goals.
"""

from __future__ import annotations

import attrs
import pytest

from dynevent.errors import InvalidConfig
from dynevent.server import inputs as ins
from dynevent.server import outputs as outs
from dynevent.server.machine import ServerConfig, State, any_description, status_message, step
from dynevent.wire import _json
from dynevent.wire.messages import DynamicEventStatus, Goal
from dynevent.wire.vocab import DynamicState, EventType, GoalStatus, RejectReason
from support.scenario import CONFIG, RMF_ROS2, next_goal, running, s, u, waiting


class OneShotClient:
    """What a stateless command-line client sends, from the status message alone."""

    def __init__(self, status: DynamicEventStatus) -> None:
        self.status = status

    def place(self, place: str, stubborn_period: float = 0.0) -> Goal:
        return Goal(
            dynamic_event_seq=self.status.dynamic_event_seq,
            event_type=EventType.NEXT,
            category="go_to_place",
            description=_json.dumps(place),
            id=self.status.id + 1,
            stubborn_period=stubborn_period,
        )

    def cancel(self) -> Goal:
        return Goal(
            dynamic_event_seq=self.status.dynamic_event_seq, event_type=EventType.CANCEL, id=self.status.id
        )

    def end(self) -> Goal:
        return Goal(dynamic_event_seq=self.status.dynamic_event_seq, event_type=EventType.FINISHED, id=0)


class Robot:
    """A server, with the status message a late-joining subscriber would receive first."""

    def __init__(self, config: ServerConfig = CONFIG) -> None:
        self.config = config
        self.state = State.new("tinyRobot", "tinyRobot1")
        self.now = s(100)
        self.uuids = 0
        self.step(ins.Begin(description='{"category": "patrol"}', event_id=7, now=self.now))

    def step(self, event: ins.Input) -> tuple[outs.Output, ...]:
        transition = step(self.state, event, self.config)
        self.state = transition.state
        self.now += s(1)
        return transition.outputs

    def latest_status(self) -> DynamicEventStatus:
        return status_message(self.state, self.now)

    def send(self, goal: Goal) -> tuple[str, tuple[outs.Output, ...]]:
        """Request and, when accepted, start one goal (rclcpp calls both in one go)."""
        self.uuids += 1
        uuid = u(self.uuids)
        outputs = self.step(ins.GoalRequested(goal_uuid=uuid, goal=goal, now=self.now))
        if outputs != (outs.GoalAccepted(goal_uuid=uuid),):
            return uuid, outputs
        return uuid, outputs + self.step(ins.GoalStarted(goal_uuid=uuid, now=self.now))

    def child_end(self, status: str = "completed") -> tuple[outs.Output, ...]:
        return self.step(ins.ChildFinished(status=status, now=self.now))


def _rejection(outputs: tuple[outs.Output, ...]) -> outs.Rejected:
    assert len(outputs) == 1 and isinstance(outputs[0], outs.GoalRejected), outputs
    return outputs[0].rejection


def _started(outputs: tuple[outs.Output, ...]) -> int:
    children = [output.id for output in outputs if isinstance(output, outs.StartChild)]
    assert len(children) == 1, outputs
    return children[0]


@pytest.mark.spec("R20.1", "R2.2", "R4.12", "R6.2")
def test_a_one_shot_client_runs_two_places_in_one_run() -> None:
    robot = Robot()
    for expected_child in (8, 9, 10):
        client = OneShotClient(robot.latest_status())
        assert client.status.dynamic_state == DynamicState.WAITING
        _, outputs = robot.send(client.place("pantry"))
        assert _started(outputs) == expected_child
        robot.child_end()
        assert robot.latest_status().id == expected_child  # the highest id used (R2.2)


@pytest.mark.spec("R20.1", "R6.2")
def test_a_next_with_id_zero_gets_the_next_id_from_the_server() -> None:
    robot = Robot()
    goal = attrs.evolve(OneShotClient(robot.latest_status()).place("pantry"), id=0)
    uuid, outputs = robot.send(goal)
    assert _started(outputs) == 8
    feedback = [output.feedback for output in outputs if isinstance(output, outs.PublishFeedback)]
    assert [item.id for item in feedback] == [8]
    assert robot.latest_status().id == 8
    answers = robot.child_end()
    assert (
        outs.AnswerGoal(
            goal_uuid=uuid,
            status=GoalStatus.SUCCEEDED,
            result=answers[0].result,  # type: ignore[attr-defined]
        )
        == answers[0]
    )
    assert answers[0].result.id == 8  # type: ignore[attr-defined]
    _, outputs = robot.send(attrs.evolve(goal, id=0))
    assert _started(outputs) == 9


@pytest.mark.spec("R20.1", "R4.14", "R9.3", "R4.13")
def test_a_one_shot_cancel_names_the_running_child_and_a_cancel_while_waiting_is_refused() -> None:
    robot = Robot()
    robot.send(OneShotClient(robot.latest_status()).place("pantry"))
    client = OneShotClient(robot.latest_status())
    assert client.status.dynamic_state == DynamicState.RUNNING
    _, outputs = robot.send(client.cancel())
    assert outs.CancelChild(id=8) in outputs
    robot.child_end("canceled")
    late = OneShotClient(robot.latest_status())
    assert late.status.dynamic_state == DynamicState.WAITING
    assert _rejection(robot.send(late.cancel())[1]).reason is RejectReason.CANCEL_IDLE


@pytest.mark.spec("R20.1", "R11.1", "R4.3")
def test_a_one_shot_finished_ends_the_run_and_a_later_next_is_refused() -> None:
    robot = Robot()
    robot.send(OneShotClient(robot.latest_status()).place("pantry"))
    robot.child_end()
    _, outputs = robot.send(OneShotClient(robot.latest_status()).end())
    answer = next(output for output in outputs if isinstance(output, outs.AnswerGoal))
    assert (answer.status, answer.result.status, answer.result.id) == (GoalStatus.SUCCEEDED, "completed", 7)
    after = OneShotClient(robot.latest_status())
    assert after.status.dynamic_state == DynamicState.INACTIVE
    assert _rejection(robot.send(after.place("pantry"))[1]).reason is RejectReason.INACTIVE


@pytest.mark.spec("R4.12", "R5.2")
def test_a_nonzero_id_that_is_not_fresh_is_still_refused() -> None:
    run = running(child_id=8)
    run.child_end()
    stale = run.request(u(2), next_goal(1, 8))
    assert _rejection(stale).reason is RejectReason.STALE_ID


# --------------------------------------------------------------------------- R3.1: the task's interruption


@pytest.mark.spec("R3.1", "R13.6", "R14.2")
def test_an_interruption_never_leaks_into_the_next_tasks_run() -> None:
    run = waiting()
    run.interrupt()
    run.submit(u(1), attrs.evolve(next_goal(1, 0), event_type=EventType.FINISHED))
    assert run.state.phase is DynamicState.INACTIVE
    run.begin(event_id=20)  # the next task is not interrupted
    outputs = run.submit(u(2), next_goal(2, 21))
    assert outs.StartChild in {type(output) for output in outputs}


@pytest.mark.spec("R3.1", "R6.3", "R14.5")
def test_a_begin_in_an_interrupted_task_defers_its_first_next() -> None:
    run = waiting()
    run.submit(u(1), attrs.evolve(next_goal(1, 0), event_type=EventType.FINISHED))
    run.step(ins.Begin(description="{}", event_id=20, now=run.now, interrupted=True))
    assert run.state.interrupted
    outputs = run.submit(u(2), next_goal(2, 21))
    assert outs.StartChild not in {type(output) for output in outputs}
    assert outs.StartChild in {type(output) for output in run.resume()}


# --------------------------------------------------------------------------- R4.17: no nested runs


@pytest.mark.spec("R4.17")
@pytest.mark.parametrize(
    "categories",
    [{"dynamic_event": any_description}, {"go_to_place": any_description, "dynamic_event": any_description}],
)
def test_dynamic_event_can_never_be_a_child_category(categories: dict[str, object]) -> None:
    with pytest.raises(InvalidConfig) as caught:
        ServerConfig(categories=categories)  # type: ignore[arg-type]
    assert caught.value.field == "categories"
    assert caught.value.value == "dynamic_event"
    assert "nested run" in str(caught.value)
    with pytest.raises(InvalidConfig):
        ServerConfig.rmf_ros2({"dynamic_event": any_description})


# --------------------------------------------------------------------------- R17.4 to R17.6: rmf_ros2's wire


@pytest.mark.spec("R17.4")
def test_rmf_ros2_mode_publishes_running_with_the_final_status_at_a_childs_end() -> None:
    run = running(config=RMF_ROS2)  # the adapter numbers the child: 2, after the run's own id 1
    outputs = run.child_end("failed")
    last = outputs[-1]
    assert isinstance(last, outs.PublishStatus)
    assert (last.message.dynamic_state, last.message.status, last.message.id) == (
        DynamicState.RUNNING,
        "failed",
        2,
    )
    assert run.state.phase is DynamicState.WAITING  # the machine itself moved on
    standard = running(child_id=5)
    message = standard.child_end("failed")[-1].message  # type: ignore[attr-defined]
    assert (message.dynamic_state, message.status) == (DynamicState.WAITING, "standby")


@pytest.mark.spec("R17.5")
def test_rmf_ros2_mode_publishes_a_status_with_every_report_even_after_a_task_cancel() -> None:
    run = running(config=RMF_ROS2)  # child 2, numbered by the adapter
    for _ in range(2):
        last = run.progress("underway")[-1]
        assert isinstance(last, outs.PublishStatus)
        assert (last.message.status, last.message.id) == ("underway", 2)
    run.task_cancel()
    last = run.progress("delayed")[-1]
    assert isinstance(last, outs.PublishStatus) and last.message.status == "delayed"
    assert run.state.status == "canceled"
    standard = running(child_id=5)
    standard.progress("delayed")
    assert not any(isinstance(output, outs.PublishStatus) for output in standard.progress("delayed"))


@pytest.mark.spec("R17.6")
def test_rmf_ros2_mode_re_serialises_the_begin_description() -> None:
    text = '{"detail": "tour", "estimate": {"description": "é", "category": "go"}, "category": "patrol"}'
    run = waiting(config=RMF_ROS2)
    run.step(ins.TaskCancel(now=run.now))
    begin = run.begin(event_id=3, description=text)[0]
    assert isinstance(begin, outs.PublishBegin)
    assert (
        begin.message.description
        == '{"category":"patrol","detail":"tour","estimate":{"category":"go","description":"é"}}'
    )
    assert run.state.description == begin.message.description
    standard = waiting()
    standard.step(ins.TaskCancel(now=standard.now))
    assert standard.begin(event_id=3, description=text)[0].message.description == text  # type: ignore[attr-defined]


# --------------------------------------------------------------------------- R5.3: goals already accepted


@pytest.mark.spec("R5.3", "R19.1")
def test_a_submitted_goal_that_lost_a_race_is_executed_then_aborted_with_the_refusal() -> None:
    run = waiting()
    assert isinstance(run.accept(next_goal(1, 8)), outs.Accepted)  # the transport's goal callback
    run.task_cancel()  # meanwhile, on another thread: the run ends
    outputs = run.step(ins.GoalSubmitted(goal_uuid=u(1), goal=next_goal(1, 8), now=run.now))
    assert outputs[0] == outs.ExecuteGoal(goal_uuid=u(1))
    answer = outputs[1]
    assert isinstance(answer, outs.AnswerGoal) and answer.status is GoalStatus.ABORTED
    assert answer.result.execution_failure.split("\n")[0] == "race condition"
    assert "no dynamic event is active" in answer.result.execution_failure
    assert len(outputs) == 2
    assert run.state == run.before


@pytest.mark.spec("R5.3", "R4.16", "R5.1")
def test_a_submitted_goal_is_requested_and_started_in_one_step() -> None:
    submitted = waiting()
    outputs = submitted.step(ins.GoalSubmitted(goal_uuid=u(1), goal=next_goal(1, 8), now=submitted.now))
    two_steps = waiting()
    two_steps.request(u(1), next_goal(1, 8))
    assert outputs == two_steps.start(u(1))
    assert submitted.state == two_steps.state
    assert submitted.step(ins.GoalSubmitted(goal_uuid=u(1), goal=next_goal(1, 9), now=submitted.now)) == (
        outs.Ignored(input="goal_submitted", why="a goal with this uuid is already open"),
    )


class PublishingRobot(Robot):
    """A robot whose status topic holds the last status message it published (not the state's own)."""

    def __init__(self, config: ServerConfig) -> None:
        self.published: DynamicEventStatus | None = None
        super().__init__(config)

    def step(self, event: ins.Input) -> tuple[outs.Output, ...]:
        outputs = super().step(event)
        for output in outputs:
            if isinstance(output, outs.PublishStatus):
                self.published = output.message
        return outputs

    def latest_status(self) -> DynamicEventStatus:
        assert self.published is not None
        return self.published


def _fresh_client_goal(robot: PublishingRobot, command: str) -> Goal:
    """What dynevent's client machine, knowing only the robot's status topic, sends for ``command``."""
    from dynevent import client

    state = client.ClientState.new("00000000000000cd")
    state = client.step(state, client.StatusReceived(message=robot.latest_status())).state
    if command == "next":
        transition = client.request_next(state, "go_to_place", '"pantry"', now=robot.now)
    else:
        transition = client.request_finish(state, now=robot.now)
    (output,) = transition.outputs
    assert isinstance(output, client.SendGoal), output
    return output.goal


@pytest.mark.spec("R20.2", "R17.4")
@pytest.mark.parametrize("final", ["completed", "failed", "canceled", "killed", "skipped"])
def test_the_client_machine_reads_a_childs_final_status_under_running_as_its_end(final: str) -> None:
    robot = PublishingRobot(RMF_ROS2)
    _, outputs = robot.send(_fresh_client_goal(robot, "next"))
    child = _started(outputs)
    robot.child_end(final)
    seen = robot.latest_status()
    assert (seen.dynamic_state, seen.status, seen.id) == (DynamicState.RUNNING, final, child)  # R17.4
    _, outputs = robot.send(_fresh_client_goal(robot, "next"))
    second = _started(outputs)
    assert second != child
    robot.child_end()
    _, outputs = robot.send(_fresh_client_goal(robot, "finish"))
    answer = next(output for output in outputs if isinstance(output, outs.AnswerGoal))
    assert answer.status is GoalStatus.SUCCEEDED


@pytest.mark.spec("R20.2", "R4.6")
@pytest.mark.parametrize("reported", ["underway", "error", "blocked", "delayed", "queued"])
def test_a_running_status_without_a_final_status_keeps_the_robot_busy_for_the_client(reported: str) -> None:
    from dynevent import client

    state = client.ClientState.new("00000000000000cd")
    running_status = DynamicEventStatus(
        dynamic_event_seq=1, dynamic_state=DynamicState.RUNNING, status=reported, id=8
    )
    state = client.step(state, client.StatusReceived(message=running_status)).state
    (output,) = client.request_next(state, "go_to_place", '"pantry"', now=0).outputs
    assert isinstance(output, client.Refused) and output.rejection.reason is RejectReason.BUSY
    (cancel,) = client.request_cancel(state, now=0).outputs
    assert isinstance(cancel, client.SendGoal) and cancel.goal.id == 8
