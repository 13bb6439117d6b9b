"""dynevent.ros over real rclpy and DDS on loopback: each spec section at least once.

The server is :class:`dynevent.ros.DynamicEventServer` with a scripted
adapter (the test drives each child through its :class:`ChildExecution`);
the clients are the binding's own, and a plain rclpy client written the way
the public one-shot client is.
"""

from __future__ import annotations

import threading
import types
from collections.abc import Iterator
from typing import Any

import pytest
from rclpy.action import ActionClient
from rmf_task_msgs.action import DynamicEvent
from rmf_task_msgs.msg import DynamicEventStatus
from ros_support import WAIT, Child, Graph, wait_for

from dynevent import client as cl
from dynevent.ros import ChildExecution, DynamicEventClient, DynamicEventServer
from dynevent.ros.server import latched
from dynevent.server import inputs as ins
from dynevent.server.machine import ServerConfig, any_description
from dynevent.testing.switched_off import switched_off
from dynevent.wire.names import action_name, status_topic

FLEET, ROBOT = "tinyRobot", "tinyRobot1"
CONFIG = ServerConfig(categories={"go_to_place": any_description, "perform_action": any_description})
SUCCEEDED, CANCELED, ABORTED = 4, 5, 6  # action_msgs/GoalStatus


class Adapter:
    """Child events the test drives by hand; stubbornness and the task's end recorded."""

    def __init__(self) -> None:
        self.started: list[ChildExecution] = []
        self.calls: list[tuple[str, int]] = []
        self.holds: list[tuple[Any, ...]] = []
        self.finished: list[str] = []

    def start(self, execution: ChildExecution) -> None:
        self.started.append(execution)

    def cancel(self, execution: ChildExecution) -> None:
        self.calls.append(("cancel", execution.id))

    def kill(self, execution: ChildExecution) -> None:
        self.calls.append(("kill", execution.id))

    def interrupt(self, execution: ChildExecution) -> None:
        self.calls.append(("interrupt", execution.id))

    def resume(self, execution: ChildExecution) -> None:
        self.calls.append(("resume", execution.id))

    # stubbornness
    def begin(self, period: float, map_name: str | None, x: float, y: float) -> None:
        self.holds.append(("begin", period, map_name))

    def hold(self, period: float, map_name: str, x: float, y: float) -> None:
        self.holds.append(("hold", period, map_name))

    def delay(self, seconds: float) -> None:
        self.holds.append(("delay",))

    def end(self) -> None:
        self.holds.append(("end",))

    def child(self, index: int = -1) -> ChildExecution:
        wait_for(lambda: len(self.started) > (index if index >= 0 else 0), "a child to start")
        return self.started[index]


def test_ros_2_and_the_interfaces_are_importable() -> None:
    import rclpy

    assert rclpy.ok is not None
    assert DynamicEvent.Goal.EVENT_TYPE_NEXT == 1


class Robot:
    """A server for one robot on its own node, and its adapter."""

    def __init__(self, graph: Graph, config: ServerConfig = CONFIG, name: str = "server") -> None:
        self.adapter = Adapter()
        self.node, self.server = graph.node(
            name,
            lambda node: (
                node,
                DynamicEventServer(
                    node,
                    FLEET,
                    ROBOT,
                    config,
                    self.adapter,
                    stubbornness=self.adapter,
                    on_finished=self.adapter.finished.append,
                ),
            ),
        )


class RawGoal:
    """One goal sent by a plain rclpy action client."""

    def __init__(self) -> None:
        self.accepted: bool | None = None
        self.handle: Any = None
        self.feedback: list[Any] = []
        self.status: int | None = None
        self.result: Any = None
        self.responded = threading.Event()
        self.ended = threading.Event()

    def wait_response(self) -> bool:
        assert self.responded.wait(WAIT), "no goal response"
        assert self.accepted is not None
        return self.accepted

    def wait_result(self) -> tuple[int, Any]:
        assert self.ended.wait(WAIT), "no result"
        assert self.status is not None
        return self.status, self.result


class RawClient:
    """A plain rclpy client, written as the public one-shot client is: the first status decides."""

    def __init__(self, graph: Graph, name: str) -> None:
        self.statuses: list[Any] = []

        def build(node: Any) -> Any:
            node.create_subscription(
                DynamicEventStatus, status_topic(FLEET, ROBOT), self.statuses.append, latched(1)
            )
            return node, ActionClient(node, DynamicEvent, action_name(FLEET, ROBOT))

        self.node, self.action = graph.node(name, build)
        assert self.action.wait_for_server(timeout_sec=WAIT)
        wait_for(lambda: bool(self.statuses), "the first status message")
        wait_for(lambda: self.node.count_publishers(status_topic(FLEET, ROBOT)) > 0, "the status publisher")

    def send(self, **fields: Any) -> RawGoal:
        goal = RawGoal()
        message = DynamicEvent.Goal(**fields)

        def on_result(future: Any) -> None:
            response = future.result()
            goal.status, goal.result = response.status, response.result
            goal.ended.set()

        def on_response(future: Any) -> None:
            goal.handle = future.result()
            goal.accepted = bool(goal.handle.accepted)
            goal.responded.set()
            if goal.accepted:
                goal.handle.get_result_async().add_done_callback(on_result)

        self.action.send_goal_async(message, feedback_callback=goal.feedback.append).add_done_callback(
            on_response
        )
        return goal

    def first_status(self) -> Any:
        return self.statuses[0]


def _client(graph: Graph, name: str = "client") -> DynamicEventClient:
    made: DynamicEventClient = graph.node(name, lambda node: DynamicEventClient(node, FLEET, ROBOT))
    assert made.wait_for_server(WAIT)
    assert made.wait_for_status(WAIT)
    return made


def _begun(graph: Graph, name: str, adapter: Adapter) -> tuple[DynamicEventServer, DynamicEventClient]:
    """A server for ``adapter`` on a node of its own, its run begun, and a client that sees it waiting."""
    server: DynamicEventServer = graph.node(
        name, lambda node: DynamicEventServer(node, FLEET, ROBOT, CONFIG, adapter)
    )
    server.begin('{"category": "patrol"}', 7)
    client = _client(graph)
    wait_for(lambda: client.state.phase == 1, "the run's WAITING status")
    return server, client


def _feedback_matched(robot: Robot) -> None:
    """Feedback is a volatile topic: wait until a client's feedback subscription is there."""
    topic = action_name(FLEET, ROBOT) + "/_action/feedback"
    wait_for(lambda: robot.node.count_subscribers(topic) > 0, "the feedback subscription")


def _outcome(run: Any) -> cl.Outcome:
    result = run.wait(WAIT)
    assert isinstance(result, cl.Outcome), result
    return result


@pytest.fixture
def robot(graph: Graph) -> Iterator[Robot]:
    made = Robot(graph)
    made.server.begin('{"category": "patrol"}', 7)
    yield made
    made.server.shutdown()


# --------------------------------------------------------------------------- §6, §7, §8: NEXT


@pytest.mark.spec("R6.4", "R7.1", "R7.2", "R8.2", "R2.2")
def test_next_with_progress_and_logs(graph: Graph, robot: Robot) -> None:
    client = _client(graph)
    _feedback_matched(robot)
    run = client.next("go_to_place", '"pantry"')
    child = robot.adapter.child()
    assert (child.id, child.category, child.parsed) == (8, "go_to_place", "pantry")
    child.underway("leaving the lobby")
    wait_for(lambda: any(progress.logs for progress in run.progress), "the log line's feedback")
    child.finished()
    outcome = _outcome(run)
    assert (outcome.kind, outcome.id, outcome.status) == (cl.OutcomeKind.COMPLETED, 8, "completed")
    logs = [entry.text for progress in run.progress for entry in progress.logs]
    assert logs == ["leaving the lobby"]
    wait_for(lambda: client.state.current_id == 8, "the WAITING status naming child 8")


# --------------------------------------------------------------------------- §9: CANCEL while running


@pytest.mark.spec("R9.3", "R8.3", "R2.1")
def test_cancel_while_running(graph: Graph, robot: Robot) -> None:
    client = _client(graph)
    run = client.next("go_to_place", '"pantry"')
    child = robot.adapter.child()
    wait_for(lambda: client.state.phase == 2, "RUNNING")
    cancel = client.cancel()
    wait_for(lambda: ("cancel", 8) in robot.adapter.calls, "the adapter told to cancel")
    assert child.stopping == "canceled" and not child.done
    assert robot.server.state.phase == 2  # RUNNING until the child really ends
    child.finished()
    assert child.done
    assert _outcome(run).kind is cl.OutcomeKind.CANCELED
    assert _outcome(cancel).kind is cl.OutcomeKind.CANCELED


# --------------------------------------------------------------------------- §10: action-level cancel


@pytest.mark.spec("R10.3", "R8.2")
def test_action_level_cancel_of_the_running_goal(graph: Graph, robot: Robot) -> None:
    raw = RawClient(graph, "raw")
    goal = raw.send(dynamic_event_seq=1, event_type=1, category="go_to_place", description='"a"', id=8)
    assert goal.wait_response()
    child = robot.adapter.child()
    cancelling = goal.handle.cancel_goal_async()
    wait_for(cancelling.done, "the cancel response")
    assert len(cancelling.result().goals_canceling) == 1
    wait_for(lambda: ("cancel", 8) in robot.adapter.calls, "the adapter told to cancel")
    child.finished()
    status, result = goal.wait_result()
    assert (status, result.status, result.id) == (CANCELED, "canceled", 8)


@pytest.mark.spec("R10.2", "R19.1")
def test_action_level_cancel_of_a_waiting_cancel_goal_is_answered_canceled(
    graph: Graph, robot: Robot
) -> None:
    """The machine answers this goal canceled inside rclpy's cancel callback; it reaches the client."""
    raw = RawClient(graph, "raw")
    next_goal = raw.send(dynamic_event_seq=1, event_type=1, category="go_to_place", description='"a"', id=8)
    assert next_goal.wait_response()
    child = robot.adapter.child()
    cancel_goal = raw.send(dynamic_event_seq=1, event_type=2, id=8)
    assert cancel_goal.wait_response()
    wait_for(lambda: ("cancel", 8) in robot.adapter.calls, "the adapter told to cancel")
    cancelling = cancel_goal.handle.cancel_goal_async()
    status, result = cancel_goal.wait_result()
    assert (status, result.execution_failure) == (CANCELED, "cancelled while not running")
    assert cancelling.done() or cancelling.result() is not None
    child.finished()
    assert next_goal.wait_result()[0] == ABORTED  # canceled early, without an action-level cancel


@pytest.mark.spec("R10.4", "R6.3", "R19.1")
def test_action_level_cancel_of_a_deferred_child_is_answered_canceled(graph: Graph, robot: Robot) -> None:
    raw = RawClient(graph, "raw")
    robot.server.interrupt()
    goal = raw.send(dynamic_event_seq=1, event_type=1, category="go_to_place", description='"a"', id=8)
    assert goal.wait_response()
    wait_for(lambda: robot.server.state.running is not None, "the deferred child")
    assert robot.adapter.started == []
    goal.handle.cancel_goal_async()
    status, result = goal.wait_result()
    assert (status, result.status, result.id) == (CANCELED, "canceled", 8)


# --------------------------------------------------------------------------- §5: races


@pytest.mark.spec("R5.3", "R19.1", "R19.2")
def test_two_nexts_racing_one_runs_and_each_gets_one_answer(graph: Graph, robot: Robot) -> None:
    first, second = RawClient(graph, "first"), RawClient(graph, "second")
    fields = {"dynamic_event_seq": 1, "event_type": 1, "category": "go_to_place", "description": '"a"'}
    goals = [first.send(id=8, **fields), second.send(id=9, **fields)]
    accepted = [goal.wait_response() for goal in goals]
    child = robot.adapter.child()
    assert len(robot.adapter.started) == 1
    child.finished()
    answers = sorted(goal.wait_result()[0] for goal, ok in zip(goals, accepted, strict=True) if ok)
    assert answers in ([SUCCEEDED], [SUCCEEDED, ABORTED])  # the loser is refused, or aborted (race)


@pytest.mark.spec("R5.3")
def test_a_goal_that_loses_a_race_between_rclpys_two_callbacks_is_aborted(graph: Graph) -> None:
    """The window between rclpy's goal callback and accepted callback, made to happen every time."""
    robot = Robot(graph)
    robot.server.begin("{}", 7)
    checked = robot.server._goal_callback

    def goal_callback_then_the_task_is_cancelled(request: Any) -> Any:
        response = checked(request)
        robot.server.task_cancel()  # another thread of the adapter, in the window
        return response

    robot.server._ros.action.register_goal_callback(goal_callback_then_the_task_is_cancelled)
    raw = RawClient(graph, "raw")
    goal = raw.send(dynamic_event_seq=1, event_type=1, category="go_to_place", description='"a"', id=8)
    assert goal.wait_response()
    status, result = goal.wait_result()
    assert status == ABORTED
    assert result.execution_failure.split("\n")[0] == "race condition"
    assert robot.adapter.started == []


# --------------------------------------------------------------------------- §11, §12, §15, §2


@pytest.mark.spec("R11.1", "R11.2")
def test_finished_ends_the_run(graph: Graph, robot: Robot) -> None:
    client = _client(graph)
    outcome = _outcome(client.finish())
    assert (outcome.kind, outcome.id) == (cl.OutcomeKind.COMPLETED, 7)
    wait_for(lambda: robot.adapter.finished == ["completed"], "the task told to move on")
    wait_for(lambda: client.state.phase == 0, "INACTIVE")


def _losing_first_answers(robot: Robot) -> list[str]:
    """The robot's action server drops the first result request of every goal unanswered, as a
    network does that loses the answer to one client while the client still hears the robot's
    status (the server's side dropped the client for a while, the client's side kept the server):
    the goals whose first request it dropped, in order."""
    action = robot.server._ros.action
    answer = action._execute_get_result_request
    dropped: list[str] = []

    async def losing(request_header_and_message: Any) -> None:
        uuid = bytes(request_header_and_message[1].goal_id.uuid).hex()
        if uuid not in dropped:
            dropped.append(uuid)
            return
        await answer(request_header_and_message)

    action._execute_get_result_request = losing
    return dropped


@pytest.mark.spec("R21.6")
def test_an_answer_lost_on_the_way_is_asked_for_again_once_the_status_shows_it_given(
    graph: Graph, robot: Robot
) -> None:
    """The first answers of a NEXT and of a FINISHED never reach the client; the statuses that show
    the child's end and the run's end do, and the client asks again and ends each goal with the
    answer the server gave (before R21.6 both waits ran out)."""
    dropped = _losing_first_answers(robot)
    client = _client(graph)
    _feedback_matched(robot)
    run = client.next("go_to_place", '"pantry"')
    robot.adapter.child().finished()
    outcome = _outcome(run)
    assert (outcome.kind, outcome.id) == (cl.OutcomeKind.COMPLETED, 8)
    finished = client.finish()
    outcome = _outcome(finished)
    assert (outcome.kind, outcome.id) == (cl.OutcomeKind.COMPLETED, 7)
    assert dropped == [run.goal_uuid, finished.goal_uuid]  # each goal's first request went unanswered


@pytest.mark.spec("R12.1", "R12.2")
def test_a_clamped_stubborn_period(graph: Graph, robot: Robot) -> None:
    client = _client(graph)
    _feedback_matched(robot)
    robot.server.update_position("L1", 1.0, 2.0)
    run = client.next("go_to_place", '"a"', stubborn_period=0.5)
    child = robot.adapter.child()
    wait_for(lambda: bool(run.progress), "the start feedback")
    warnings = [entry.text for progress in run.progress for entry in progress.logs if entry.tier == "warning"]
    assert warnings and "below the minimum" in warnings[0]
    child.finished()
    _outcome(run)
    wait_for(lambda: ("begin", 2.0, "L1") in robot.adapter.holds, "stubbornness for 2 s")


@pytest.mark.spec("R12.3")
def test_a_robot_has_a_timer_only_while_a_stubbornness_holds(graph: Graph, robot: Robot) -> None:
    """An idle robot costs no timer (each costs CPU at every executor wake-up); the stubborn refresh
    runs from the hold's start to its end, and refreshes from the robot's new place."""
    client = _client(graph)
    _feedback_matched(robot)
    assert list(robot.node.timers) == []
    robot.server.update_position("L1", 1.0, 2.0)
    run = client.next("go_to_place", '"a"', stubborn_period=5.0)
    robot.adapter.child().finished()
    _outcome(run)
    wait_for(lambda: len(list(robot.node.timers)) == 1, "the refresh timer")
    robot.server.update_position("L1", 9.0, 2.0)  # moved: the next refresh holds from here
    wait_for(lambda: ("hold", 5.0, "L1") in robot.adapter.holds, "a refreshed hold (1 s period)", 5.0)
    second = client.next("go_to_place", '"b"')  # its start ends the stubbornness
    robot.adapter.child(1)
    wait_for(lambda: ("end",) in robot.adapter.holds, "the hold's end")
    wait_for(lambda: list(robot.node.timers) == [], "no timer after the hold")
    robot.adapter.child(1).finished()
    _outcome(second)


def test_a_robot_adds_to_every_executor_pass_its_action_server_and_wake_up_only(graph: Graph) -> None:
    """Each waitable of a node is visited at every pass of the executor.  A robot's server adds its
    action server and the guard condition that wakes its drain, and nothing else: its publishers
    (status, begin, the fleet's begin) have none of rclpy's default QoS-event handlers, which had
    added two waitables each (docs/performance.md)."""

    def counts(node: Any) -> tuple[int, int, int]:
        return len(list(node.waitables)), len(list(node.guards)), len(list(node.timers))

    before: dict[str, tuple[int, int, int]] = {}

    def make(node: Any) -> DynamicEventServer:
        before["node"] = counts(node)
        return DynamicEventServer(node, FLEET, ROBOT, CONFIG, Adapter())

    server: DynamicEventServer = graph.node("entities", make)
    server.begin('{"category": "patrol"}', 7)
    waitables, guards, timers = before["node"]
    assert counts(server._node) == (waitables + 1, guards + 1, timers)
    server.shutdown()


def test_a_goals_uuid_formats_as_hex_in_rclpys_debug_messages_and_travels_whole(graph: Graph) -> None:
    """rclpy's action server formats each goal's UUID into its debug messages whether or not they are
    logged, where numpy formats the array slowly: the server's goal handles hold the UUID in an
    array that formats as 32 hex digits, is a numpy array to the generated C conversion (the name its
    debug build asserts), and travels whole (docs/performance.md)."""
    from action_msgs.msg import GoalInfo
    from rclpy.serialization import deserialize_message, serialize_message
    from unique_identifier_msgs.msg import UUID

    from dynevent.ros import convert

    adapter = Adapter()
    server, client = _begun(graph, "uuids", adapter)
    run = client.next("go_to_place", '"pantry"')
    adapter.child()
    ((uuid, handle),) = server._handles.items()
    array = handle.goal_id.uuid
    assert f"{array}" == uuid and type(array).__name__ == "numpy.ndarray"
    info = GoalInfo(goal_id=handle.goal_id)
    assert bytes(deserialize_message(serialize_message(info), GoalInfo).goal_id.uuid).hex() == uuid
    assert f"{convert.quiet_uuid(UUID(uuid=list(range(16)))).uuid}" == bytes(range(16)).hex()
    adapter.child().finished()
    assert _outcome(run).kind is cl.OutcomeKind.COMPLETED
    server.shutdown()


@pytest.mark.spec("R15.1", "R19.1")
def test_shutdown_answers_open_goals(graph: Graph) -> None:
    robot = Robot(graph)
    robot.server.begin("{}", 7)
    raw = RawClient(graph, "raw")
    next_goal = raw.send(dynamic_event_seq=1, event_type=1, category="go_to_place", description='"a"', id=8)
    assert next_goal.wait_response()
    robot.adapter.child()
    cancel_goal = raw.send(dynamic_event_seq=1, event_type=2, id=8)
    assert cancel_goal.wait_response()
    robot.server.shutdown()
    for goal in (next_goal, cancel_goal):
        status, result = goal.wait_result()
        assert (status, result.execution_failure) == (ABORTED, "shutting down")
    late = raw.send(dynamic_event_seq=1, event_type=1, category="go_to_place", description='"a"', id=9)
    assert not late.wait_response()  # refused (R4.1)


@pytest.mark.spec("R2.2", "R2.3", "R1.4")
def test_a_late_joining_status_subscriber_gets_the_current_status(graph: Graph, robot: Robot) -> None:
    client = _client(graph)
    run = client.next("go_to_place", '"a"')
    robot.adapter.child().finished()
    _outcome(run)
    wait_for(lambda: client.state.current_id == 8 and client.state.phase == 1, "WAITING, id 8")
    late = RawClient(graph, "late")
    first = late.first_status()
    assert (first.dynamic_event_seq, first.dynamic_state, first.status, first.id) == (1, 1, "standby", 8)


@pytest.mark.spec("R2.3")
def test_a_server_begun_before_it_spins_says_waiting_first(graph: Graph) -> None:
    """A client that acts on the first status it sees must never see a passing INACTIVE."""
    seen: list[Any] = []
    graph.node(
        "watching",
        lambda node: node.create_subscription(
            DynamicEventStatus, status_topic(FLEET, ROBOT), seen.append, latched(10)
        ),
    )

    def build(node: Any) -> DynamicEventServer:
        server = DynamicEventServer(node, FLEET, ROBOT, CONFIG, Adapter())
        server.begin('{"category": "patrol"}', 7)
        wait_for(lambda: node.count_subscribers(status_topic(FLEET, ROBOT)) > 0, "the watcher")
        return server

    graph.node("begun", build)
    wait_for(lambda: bool(seen), "the first status")
    assert (seen[0].dynamic_event_seq, seen[0].dynamic_state, seen[0].status) == (1, 1, "standby")


# --------------------------------------------------------------------------- R20.1: the public client's way


@pytest.mark.spec("R20.1", "R4.13", "R4.3")
def test_a_plain_one_shot_client_drives_a_whole_run(graph: Graph, robot: Robot) -> None:
    """Each goal from a fresh client whose first status decides seq and id, as rmf_demos' client does."""
    watcher = _client(graph, "watcher")  # the status on the wire, which the next one-shot client meets

    def one_shot(name: str, **fields: Any) -> tuple[RawGoal, Any]:
        raw = RawClient(graph, name)
        status = raw.first_status()
        if fields.get("event_type") == 1:
            fields["id"] = status.id + 1
        elif fields.get("event_type") == 2:
            fields["id"] = status.id
        return raw.send(dynamic_event_seq=status.dynamic_event_seq, **fields), status

    for index, place in enumerate(("pantry", "lobby")):
        goal, _ = one_shot(f"place{index}", event_type=1, category="go_to_place", description=f'"{place}"')
        assert goal.wait_response()
        robot.adapter.child(index).finished()
        status, result = goal.wait_result()
        assert (status, result.id) == (SUCCEEDED, 8 + index)
        wait_for(
            lambda last=8 + index: (watcher.state.phase, watcher.state.current_id) == (1, last),
            "WAITING on the wire",
        )
    goal, _ = one_shot("place2", event_type=1, category="go_to_place", description='"dock"')
    assert goal.wait_response()
    robot.adapter.child(2)
    cancel, seen = one_shot("cancel", event_type=2)
    assert seen.dynamic_state == 2 and cancel.wait_response()
    robot.adapter.child(2).finished()
    assert cancel.wait_result()[0] == SUCCEEDED
    wait_for(lambda: (watcher.state.phase, watcher.state.current_id) == (1, 10), "WAITING on the wire")
    idle_cancel, _ = one_shot("idle", event_type=2)
    assert not idle_cancel.wait_response()
    finished, _ = one_shot("end", event_type=3, id=0)
    assert finished.wait_response()
    assert finished.wait_result()[0] == SUCCEEDED
    wait_for(lambda: watcher.state.phase == 0, "INACTIVE on the wire")
    after, _ = one_shot("after", event_type=1, category="go_to_place", description='"x"')
    assert not after.wait_response()


# --------------------------------------------------------------------------- two processes: docs/ros.md


@pytest.mark.spec("R6.4", "R7.1", "R8.2", "R11.1", "R15.1")
def test_the_documented_adapter_serves_a_client_in_another_process(graph: Graph) -> None:
    from pathlib import Path

    example = Path(__file__).resolve().parents[2] / "docs" / "examples" / "ros_adapter.py"
    adapter = Child([str(example), "--robot", ROBOT, "--robot", "tinyRobot2", "--seconds", "60"])
    try:
        adapter.wait_line("ready")
        client = _client(graph)
        other: DynamicEventClient = graph.node(
            "other", lambda node: DynamicEventClient(node, FLEET, "tinyRobot2")
        )
        assert other.wait_for_status(WAIT) and other.state.current_id == 2  # its own run, id 2
        run = client.next("go_to_place", '"pantry"')
        outcome = _outcome(run)
        assert (outcome.kind, outcome.id) == (cl.OutcomeKind.COMPLETED, 2)
        failed = _outcome(client.next("go_to_place", '"nowhere"'))
        assert (failed.kind, failed.status) == (cl.OutcomeKind.FAILED, "failed")
        refused = client.next("go_to_place", "42").wait(WAIT)  # JSON, not a place: the server refuses it
        assert isinstance(refused, cl.Outcome) and refused.kind is cl.OutcomeKind.REJECTED
        assert _outcome(client.finish()).kind is cl.OutcomeKind.COMPLETED
    except AssertionError as failure:
        raise AssertionError(f"{failure}\n--- the adapter printed:\n{adapter.output}") from failure
    finally:
        code = adapter.stop()
    assert code == 0, adapter.output


# --------------------------------------------------------------------------- §16: the description service


@pytest.mark.spec("R16.1", "R16.2")
def test_the_description_service_answers_where_its_type_exists(graph: Graph) -> None:
    from rmf_task_msgs.srv import DescribeDynamicEvent

    from dynevent.wire.names import description_service

    server = graph.node(
        "described",
        lambda node: DynamicEventServer(
            node, FLEET, ROBOT, CONFIG, Adapter(), description_service=DescribeDynamicEvent
        ),
    )
    asker = graph.node(
        "asker", lambda node: node.create_client(DescribeDynamicEvent, description_service(FLEET, ROBOT))
    )
    assert asker.wait_for_service(timeout_sec=WAIT)

    def ask() -> Any:
        future = asker.call_async(DescribeDynamicEvent.Request())
        wait_for(future.done, "the description answer")
        return future.result()

    answer = ask()
    assert (answer.running, answer.status, answer.description, answer.id) == (False, "", "", 0)
    server.begin('{"category": "patrol"}', 7)
    answer = ask()
    assert (answer.running, answer.status, answer.description, answer.id) == (
        True,
        "standby",
        '{"category": "patrol"}',
        7,
    )
    # a machine that gives no answer (the test kit's R16.1 switched off, with the run ended) is answered
    # with the defaults: the exception it was ended the thread of every robot of the node's lane
    server.step(ins.Shutdown(now=server.now()))
    with switched_off("R16.1"):
        answer = ask()
    assert (answer.running, answer.status, answer.description, answer.id) == (False, "", "", 0)
    answer = ask()  # and the node still answers
    assert (answer.running, answer.status, answer.description, answer.id) == (False, "", "", 0)


# --------------------------------------------------------------------------- converters at the edge


@pytest.mark.spec("R1.2", "R4.15")
def test_a_goal_the_mirrors_refuse_is_rejected_with_its_reason_not_a_traceback(graph: Graph) -> None:
    from types import SimpleNamespace

    from dynevent.errors import InvalidMessage
    from dynevent.ros import convert

    robot = Robot(graph)
    robot.server.begin("{}", 7)
    hostile = SimpleNamespace(
        dynamic_event_seq=1,
        event_type=1,
        category="go_to_place",
        description='"a"',
        id=8,
        stubborn_period=1e39,
    )
    with pytest.raises(InvalidMessage, match="stubborn_period"):
        convert.goal_from_ros(hostile)
    from rclpy.action import GoalResponse

    assert robot.server._goal_callback(hostile) == GoalResponse.REJECT
    assert convert.uuid_from_ros(list(range(16))) == bytes(range(16)).hex()
    with pytest.raises(InvalidMessage, match="16 bytes"):
        convert.uuid_from_ros([1, 2, 3])


@pytest.mark.spec("R4.15", "R5.3")
def test_on_step_sees_every_goal_a_refused_one_by_its_request_with_its_uuid(graph: Graph) -> None:
    """rclpy's goal callback gets the goal alone; the server learns the request's UUID all the same,
    so a refused goal is a step of its own (request, refusal with its reason), and an accepted one the
    step of its submission."""
    from dynevent.server import inputs as ins
    from dynevent.server import outputs as outs

    steps: list[tuple[Any, tuple[Any, ...]]] = []

    def on_step(event: Any, outputs: tuple[Any, ...]) -> None:
        steps.append((event, outputs))

    server = graph.node(
        "stepped", lambda node: DynamicEventServer(node, FLEET, ROBOT, CONFIG, Adapter(), on_step=on_step)
    )
    server.begin("{}", 7)
    raw = RawClient(graph, "raw")
    stale = raw.send(dynamic_event_seq=9, event_type=3)
    assert stale.wait_response() is False
    finished = raw.send(dynamic_event_seq=1, event_type=3)
    assert finished.wait_response() is True
    wait_for(lambda: any(isinstance(event, ins.GoalSubmitted) for event, _ in steps), "the submitted step")
    goals = [
        (event, outputs)
        for event, outputs in steps
        if isinstance(event, (ins.GoalRequested, ins.GoalSubmitted))
    ]
    assert [type(event) for event, _ in goals] == [ins.GoalRequested, ins.GoalSubmitted]
    (refused, outputs), (submitted, _) = goals
    assert refused.goal_uuid == bytes(stale.handle.goal_id.uuid).hex()
    assert len(outputs) == 1 and isinstance(outputs[0], outs.GoalRejected)
    assert outputs[0].goal_uuid == refused.goal_uuid and outputs[0].rejection.reason.value == "seq_mismatch"
    assert submitted.goal_uuid == bytes(finished.handle.goal_id.uuid).hex()
    assert refused.goal_uuid != submitted.goal_uuid
    server.shutdown()


def test_a_received_message_the_mirror_refuses_is_the_senders_fault() -> None:
    """Conversions of received ROS messages raise MalformedMessage (a RemoteError), never the
    LocalError a value built here would; a goal UUID comes in rclpy's own shape (a uint8 array)."""
    from unique_identifier_msgs.msg import UUID

    from dynevent.errors import LocalError, MalformedMessage, RemoteError
    from dynevent.ros import convert

    with pytest.raises(MalformedMessage) as refused:
        convert.uuid_from_ros(list(range(15)))  # the raw uint8 values of a UUID, one short
    assert isinstance(refused.value, RemoteError) and not isinstance(refused.value, LocalError)
    assert refused.value.field == "uuid", refused.value
    assert convert.uuid_from_ros(UUID(uuid=list(range(16)))) == "000102030405060708090a0b0c0d0e0f"


@pytest.mark.spec("R21.1", "R21.4")
def test_a_restarted_server_holds_its_restart_answers_before_it_first_spins(graph: Graph) -> None:
    """A goal running when the process before ended is answered ``server restarted`` at the restart
    (R21.1), and a client that asks for its result from then on gets that answer (R21.4): the answer
    is held at the restart's step, not at the drain that carries the step out, which the executor may
    take after the client's request (under load a client once got 'goal lost in a server restart')."""
    from dynevent.server import inputs as ins
    from dynevent.server.holder import RobotServer
    from dynevent.wire.messages import Goal
    from dynevent.wire.vocab import Failure, GoalStatus

    before = RobotServer(FLEET, ROBOT, CONFIG)
    before.step(ins.Begin(description="{}", event_id=1, now=1))
    goal = Goal(dynamic_event_seq=1, event_type=1, category="go_to_place", description='"a"', id=2)
    uuid = "5" * 32
    before.step(ins.GoalSubmitted(goal_uuid=uuid, goal=goal, now=2))
    assert before.state.running is not None and before.state.running.goal_uuid == uuid
    held: list[Any] = []

    def build(node: Any) -> DynamicEventServer:
        server = DynamicEventServer(node, FLEET, ROBOT, CONFIG, Adapter(), state=before.state)
        server.restart()
        held.append(server._ros.action._owed(uuid))  # before the node first spins: no drain yet
        return server

    graph.node("restarted", build)
    (answer,) = held
    assert answer is not None, "the restart's answer is not held for a client that asks now"
    assert (answer.status, answer.result.execution_failure) == (GoalStatus.ABORTED, Failure.RESTART.value)


class _CountedWake:
    """A server's wake-up guard condition, counted where the server triggers it."""

    def __init__(self, wake: Any) -> None:
        self.wake = wake
        self.triggers = 0

    def trigger(self) -> None:
        self.triggers += 1
        self.wake.trigger()


class _AtOnce(Adapter):
    """Finishes each child inside its start callback, as an adapter whose child has nothing to do."""

    def start(self, execution: ChildExecution) -> None:
        super().start(execution)
        execution.finished()


def test_a_step_inside_the_drain_wakes_no_executor_and_one_from_another_thread_does(graph: Graph) -> None:
    """An adapter that steps the server from a callback of the drain (a child finished in its start) adds
    to the outbox that drain is carrying out: the executor is not woken for a drain of its own (one
    wake-up less on a goal's round trip, docs/performance.md).  A step from any other thread wakes it."""
    server, client = _begun(graph, "at_once", _AtOnce())
    counted = _CountedWake(server._ros.wake)
    server._ros.wake = counted
    try:
        outcome = _outcome(client.next("go_to_place", '"pantry"'))
        assert (outcome.kind, outcome.id) == (cl.OutcomeKind.COMPLETED, 8)
        assert counted.triggers == 0
        server.update_position("L1", 1.0, 2.0)  # the adapter's thread: a step the executor must carry out
        assert counted.triggers == 1
    finally:
        server._ros.wake = counted.wake
        server.shutdown()


def _matched(total: int, current: int, current_change: int) -> Any:
    """A status publisher's matched event as rclpy sums it since the last one taken (its own type has
    no constructor from Python)."""
    return types.SimpleNamespace(
        total_count=total,
        total_count_change=total,
        current_count=current,
        current_count_change=current_change,
    )


@pytest.mark.spec("R21.4")
def test_the_first_match_taken_after_the_status_was_heard_asks_for_no_result(graph: Graph) -> None:
    """The executor runs the status's callback, a goal is sent, and only then is the status publisher's
    matched event taken (found with ``dynevent send``: a result request asked then reached the server
    before the goal's request, was answered unknown, and the goal ended ``goal lost`` while the server
    ran it).  That event is the match of the process the client heard: it asks for nothing.  A later
    match, or a first that sums two publishers (one gone, one come), is a new process: it asks."""
    heard = DynamicEventStatus(dynamic_event_seq=1, dynamic_state=1, status="standby", id=1)
    for name, first, asks in (("late", _matched(1, 1, 1), 0), ("two", _matched(2, 1, 1), 1)):
        client: DynamicEventClient = graph.node(
            name, lambda node: DynamicEventClient(node, FLEET, "nobodyHere")
        )
        client._on_status(heard)  # the callbacks, in the order of the race: no server answers here
        client.next("go_to_place", '{"one_of": ["pantry"]}')
        client._on_contact_event(first)
        (goal,) = client.state.goals
        assert goal.asks == asks, (name, goal)
        client._on_contact_event(_matched(1, 1, 0))  # a process gone and its successor come
        (goal,) = client.state.goals
        assert goal.asks == 1, (name, goal)  # asked at once (its count from this contact on)
