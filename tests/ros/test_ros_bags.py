"""Bags whose messages ROS 2 itself serialised (rclpy's type support, not the reader's definitions),
written by rosbags' writer: ``dynevent check`` decodes them with the project's interface files and
judges them, which holds those definitions, the action's derived types included, to ROS's own."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pytest
from action_msgs.msg import GoalInfo
from action_msgs.srv import CancelGoal
from rclpy.serialization import serialize_message
from rmf_task_msgs.action import DynamicEvent
from rmf_task_msgs.msg import DynamicEventDescription, DynamicEventStatus
from rosbags.rosbag2 import StoragePlugin, Writer
from service_msgs.msg import ServiceEventInfo
from unique_identifier_msgs.msg import UUID

from dynevent.bags.reader import _definitions, check_bag

ACTION = "/rmf/dynamic_event/command/tinyRobot/r1"
T0 = 1_700_000_000 * 10**9
UNHASHED = "RIHS01_" + "0" * 64


def _types() -> dict[str, Any]:
    return {
        "rmf_task_msgs/msg/DynamicEventStatus": DynamicEventStatus,
        "rmf_task_msgs/msg/DynamicEventDescription": DynamicEventDescription,
        "rmf_task_msgs/action/DynamicEvent_FeedbackMessage": DynamicEvent.Impl.FeedbackMessage,
        "rmf_task_msgs/action/DynamicEvent_SendGoal_Event": DynamicEvent.Impl.SendGoalService.Event,
        "rmf_task_msgs/action/DynamicEvent_GetResult_Event": DynamicEvent.Impl.GetResultService.Event,
        "action_msgs/srv/CancelGoal_Event": CancelGoal.Event,
    }


def _event(event_type: type, kind: int, call: int, request: Any = None, response: Any = None) -> Any:
    """As ROS 2 introspection records a call: the request in the request event, the response alone in
    the response event, paired by the client's GID and the sequence number ``call``."""
    info = ServiceEventInfo(event_type=kind, sequence_number=call)  # no stamp: the bag time orders it
    return event_type(info=info, request=[] if request is None else [request],
                      response=[] if response is None else [response])  # fmt: skip


def _conversation(stale: bool) -> list[tuple[str, str, Any]]:
    """begin, WAITING, a NEXT run to its end with feedback and an action-level cancel refused after it,
    FINISHED (for run 0 when ``stale``: a goal the server must refuse, accepted)."""
    uuid = UUID(uuid=[1] * 16)
    finished_uuid = UUID(uuid=[2] * 16)
    status = "/rmf/dynamic_event/status/tinyRobot/r1"
    next_goal = DynamicEvent.Goal(dynamic_event_seq=1, event_type=1, category="go_to_place",
                                  description='"pantry"', id=1)  # fmt: skip
    send = DynamicEvent.Impl.SendGoalService
    get = DynamicEvent.Impl.GetResultService
    finished_goal = DynamicEvent.Goal(dynamic_event_seq=0 if stale else 1, event_type=3)
    return [
        ("/rmf/dynamic_event/begin/tinyRobot/r1", "rmf_task_msgs/msg/DynamicEventDescription",
         DynamicEventDescription(fleet="tinyRobot", robot="r1", dynamic_event_seq=1, description="{}")),
        (status, "rmf_task_msgs/msg/DynamicEventStatus",
         DynamicEventStatus(dynamic_event_seq=1, dynamic_state=1, status="standby", id=0)),
        (f"{ACTION}/_action/send_goal/_service_event", "rmf_task_msgs/action/DynamicEvent_SendGoal_Event",
         _event(send.Event, 1, 1, send.Request(goal_id=uuid, goal=next_goal))),
        (f"{ACTION}/_action/send_goal/_service_event", "rmf_task_msgs/action/DynamicEvent_SendGoal_Event",
         _event(send.Event, 2, 1, response=send.Response(accepted=True))),
        (f"{ACTION}/_action/feedback", "rmf_task_msgs/action/DynamicEvent_FeedbackMessage",
         DynamicEvent.Impl.FeedbackMessage(
             goal_id=uuid, feedback=DynamicEvent.Feedback(status="underway", id=1))),
        (status, "rmf_task_msgs/msg/DynamicEventStatus",
         DynamicEventStatus(dynamic_event_seq=1, dynamic_state=2, status="underway", id=1)),
        (f"{ACTION}/_action/get_result/_service_event", "rmf_task_msgs/action/DynamicEvent_GetResult_Event",
         _event(get.Event, 1, 1, get.Request(goal_id=uuid))),
        (f"{ACTION}/_action/get_result/_service_event", "rmf_task_msgs/action/DynamicEvent_GetResult_Event",
         _event(get.Event, 2, 1,
                response=get.Response(status=4, result=DynamicEvent.Result(status="completed", id=1)))),
        (status, "rmf_task_msgs/msg/DynamicEventStatus",
         DynamicEventStatus(dynamic_event_seq=1, dynamic_state=1, status="standby", id=1)),
        (f"{ACTION}/_action/cancel_goal/_service_event", "action_msgs/srv/CancelGoal_Event",
         _event(CancelGoal.Event, 1, 1, CancelGoal.Request(goal_info=GoalInfo(goal_id=uuid)))),
        (f"{ACTION}/_action/cancel_goal/_service_event", "action_msgs/srv/CancelGoal_Event",
         _event(CancelGoal.Event, 2, 1, response=CancelGoal.Response(return_code=3))),
        (f"{ACTION}/_action/send_goal/_service_event", "rmf_task_msgs/action/DynamicEvent_SendGoal_Event",
         _event(send.Event, 1, 2, send.Request(goal_id=finished_uuid, goal=finished_goal))),
        (f"{ACTION}/_action/send_goal/_service_event", "rmf_task_msgs/action/DynamicEvent_SendGoal_Event",
         _event(send.Event, 2, 2, response=send.Response(accepted=True))),
        (f"{ACTION}/_action/get_result/_service_event", "rmf_task_msgs/action/DynamicEvent_GetResult_Event",
         _event(get.Event, 1, 2, get.Request(goal_id=finished_uuid))),
        (f"{ACTION}/_action/get_result/_service_event", "rmf_task_msgs/action/DynamicEvent_GetResult_Event",
         _event(get.Event, 2, 2,
                response=get.Response(status=4, result=DynamicEvent.Result(status="completed", id=0)))),
        (status, "rmf_task_msgs/msg/DynamicEventStatus",
         DynamicEventStatus(dynamic_event_seq=1, dynamic_state=0, status="uninitialized", id=0)),
    ]  # fmt: skip


def _write(path: Path, storage: StoragePlugin, messages: list[tuple[str, str, Any]]) -> Path:
    definitions = _definitions()
    with Writer(path, version=9, storage_plugin=storage) as writer:
        connections: dict[str, Any] = {}
        for index, (topic, msgtype, message) in enumerate(messages):
            if topic not in connections:
                connections[topic] = writer.add_connection(
                    topic, msgtype, msgdef=definitions.get(msgtype, ""), rihs01=UNHASHED
                )
            writer.write(connections[topic], T0 + index * 10**8, serialize_message(message))
    return path


@pytest.mark.spec("R4.2", "R10.5")
@pytest.mark.parametrize("storage", [StoragePlugin.MCAP, StoragePlugin.SQLITE3], ids=["mcap", "sqlite3"])
def test_messages_ros_serialised_are_decoded_and_judged(tmp_path: Path, storage: StoragePlugin) -> None:
    assert set(_types()) <= set(_definitions()) | {"rmf_task_msgs/msg/DynamicEventStatus"}
    clean = check_bag(_write(tmp_path / "clean", storage, _conversation(stale=False)))
    robot = clean.robots[0]
    assert clean.clean and robot.report is not None and robot.report.records == 14, clean
    assert robot.absent == () and robot.refused == 0
    stale = check_bag(_write(tmp_path / "stale", storage, _conversation(stale=True)))
    findings = stale.robots[0].report.findings  # type: ignore[union-attr]
    assert findings and (findings[0].rule, findings[0].line) == ("R4.2", T0 + 12 * 10**8), findings


# --------------------------------------------------------------------------- dynevent record, over DDS

ROBOT = "recorded1"
SERVICE_EVENTS = [f"/rmf/dynamic_event/command/tinyRobot/{ROBOT}/_action/{name}/_service_event"
                  for name in ("send_goal", "get_result")]  # fmt: skip


def _session(tmp_path: Path, serve_args: list[str], pause: float = 0.0) -> Path:
    """serve, and dynevent record of its robot, while send runs a NEXT and, ``pause`` seconds after,
    a FINISHED; the bag."""
    import json
    import subprocess
    import sys
    import time

    from ros_support import Child, child_env, finish, wait_for

    config = tmp_path / "fleet.json"
    config.write_text(json.dumps({"categories": {"go_to_place": {"duration": 0.5, "report_every": 0.1}},
                                  "rebegin": 0}), encoding="utf-8")  # fmt: skip
    serve = Child(["-m", "dynevent", "serve", "--robot", ROBOT, "--config", str(config), *serve_args])
    bag = tmp_path / "bag"
    record = None
    try:
        serve.wait_line("serving ")
        record = Child(["-m", "dynevent", "record", "-o", str(bag), "--fleet", "tinyRobot", "--robot", ROBOT])
        record.wait_line(f"recording /rmf/dynamic_event/status/tinyRobot/{ROBOT}")
        # the recorder hears serve on each topic before a goal is sent: "recording" is said when its
        # subscription is made, which DDS discovery between the two processes may match seconds later
        # (under load a recorder was once matched after the NEXT's child had ended, and once kept only
        # the latched end of it; the graph as a third process sees it is no proof of the match)
        action = f"/rmf/dynamic_event/command/tinyRobot/{ROBOT}/_action"
        heard = [f"/rmf/dynamic_event/status/tinyRobot/{ROBOT}", f"{action}/feedback", f"{action}/status"]
        if "--no-judge" not in serve_args:  # serve's introspection: the goals and their answers
            heard += SERVICE_EVENTS
        for topic in heard:
            record.wait_line(f"hearing {topic}")
        for args in (["--place", "pantry"], ["--end"]):
            command = ["-m", "dynevent", "send", "--robot", ROBOT, "--timeout", "20", *args]
            process = subprocess.Popen(
                [sys.executable, *command],
                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=child_env(),
            )  # fmt: skip
            sent = finish(process, 60)
            assert sent.returncode == 0, sent.stdout + sent.stderr
            time.sleep(pause)
        wait_for(lambda: serve.saw("status: INACTIVE"), "the run's end at serve")
    finally:
        if record is not None:
            assert record.stop() == 0, record.output
        serve.stop()
    assert record.saw("recorded "), record.output
    return bag


@pytest.mark.spec("R19.1", "R11.1")
def test_a_recorded_session_with_introspection_is_judged_clean(tmp_path: Path) -> None:
    """serve judges its clients, so its action's introspection is on: the bag holds the goals and
    answers, rosbags reads it, and check judges it clean and whole."""
    from rosbags.rosbag2 import Reader

    bag = _session(tmp_path, [])
    with Reader(bag) as reader:  # the independent reader opens what dynevent record wrote
        topics = {connection.topic for connection in reader.connections}
        assert set(SERVICE_EVENTS) <= topics and reader.message_count > 10
    report = check_bag(bag)
    robot = next(item for item in report.robots if item.robot == ROBOT)
    assert report.clean and robot.report is not None, report
    assert robot.report.records > 10 and robot.absent == (), robot
    _read_by_others(bag)


def _read_by_others(bag: Path) -> None:
    """Readers that take each type from the definitions the bag holds decode what record wrote:
    rosbags every topic, Foxglove's decoder the status, begin and goal status topics (ROS's parser
    names no type an action derives), to the same messages."""
    from rosbags.rosbag2 import Reader

    from support.bag_readers import read_with_foxglove, read_with_rosbags

    with Reader(bag) as reader:
        counts = {connection.topic: connection.msgcount for connection in reader.connections}
    by_rosbags = read_with_rosbags(bag)
    assert {topic: len(items) for topic, items in by_rosbags.items()} == counts
    by_foxglove, _ = read_with_foxglove(bag)
    status = f"/rmf/dynamic_event/status/tinyRobot/{ROBOT}"
    assert len(by_foxglove[status]) == counts[status] and by_foxglove[status][-1].dynamic_state == 0
    assert [item.id for item in by_foxglove[status]] == [item.id for item in by_rosbags[status]]


@pytest.mark.spec("R2.2", "R7.1", "R7.3", "R19.1")
def test_a_recorded_session_without_introspection_is_a_partial_view(tmp_path: Path) -> None:
    """Without introspection the bag holds the topics alone: the robot is a partial view, judged from
    its begins, statuses, feedback and goal statuses, and clean."""
    bag = _session(tmp_path, ["--no-judge"])
    report = check_bag(bag)
    robot = next(item for item in report.robots if item.robot == ROBOT)
    assert report.clean and robot.partial, report
    assert "goals and their responses (send_goal introspection)" in robot.absent
    assert {"status", "begin", "feedback", "goal status"} <= set(robot.channels), robot
    assert robot.report.records > 10, robot
    _read_by_others(bag)


@pytest.mark.spec("R2.2", "R8.4", "R17.4")
def test_a_partial_view_of_rmf_ros2_finds_the_running_status_after_a_childs_end(tmp_path: Path) -> None:
    """serve in rmf_ros2 mode publishes RUNNING with the child's final status at its end (D2), and the
    topic keeps saying so: a bag without introspection shows it, one finding at the NEXT's answer."""
    bag = _session(tmp_path, ["--no-judge", "--compatibility", "rmf_ros2"], pause=1.5)
    report = check_bag(bag)
    robot = next(item for item in report.robots if item.robot == ROBOT)
    assert robot.partial, robot
    assert [(finding.rule, finding.code) for finding in robot.report.findings] == [
        ("R2.2", "status_mismatch")
    ], robot.report.findings


def test_record_shows_its_progress_on_a_terminal_and_stops_at_its_time(tmp_path: Path) -> None:
    """On a terminal, record keeps one progress line (topics, messages, bytes) up to date on standard
    error, as every command's progress, erased before each line it prints and at the end, and says
    what it recorded; --seconds stops it cleanly (the bag closed, metadata.yaml written)."""
    import os
    import pty
    import re
    import select
    import subprocess
    import sys
    import time

    from ros_support import child_env, finish

    primary, secondary = pty.openpty()
    bag = tmp_path / "bag"
    command = [sys.executable, "-m", "dynevent", "record", "-o", str(bag), "--seconds", "4"]
    process = subprocess.Popen(command, stdin=subprocess.DEVNULL, stdout=secondary, stderr=secondary,
                               text=True, env=child_env())  # fmt: skip
    os.close(secondary)
    output = b""
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        ready, _, _ = select.select([primary], [], [], 1.0)
        if not ready:
            continue
        try:
            chunk = os.read(primary, 4096)
        except OSError:  # the terminal closed: the process ended
            break
        if not chunk:
            break
        output += chunk
    os.close(primary)
    done = finish(process, 30)
    text = output.decode("utf-8", "replace")
    assert done.returncode == 0, text
    assert re.search(r"\rrecording \S+: \d+ topics, [\d,]+ messages, [\d,]+ bytes\x1b\[K", text), text
    # the line is erased before the summary: nothing printed is written over it
    assert re.search(r"\r\x1b\[K(\r?\n)*recorded \d+ messages \(\d+ bytes\) on \d+ topics into ", text), text
    assert (bag / "metadata.yaml").is_file()


def test_the_recorder_keeps_when_each_message_arrived_not_when_it_got_to_it() -> None:
    """A recorder that falls behind (a busy machine) takes what DDS holds for it in a burst: each
    message is still written with the time the middleware received it, so the bag keeps the order
    and the spacing of what happened, which the judge reads (a burst once made the judge read a
    CANCEL's answer before the feedback that named its child), and with the time it was sent."""
    import time

    from dynevent.ros.qos import latched
    from dynevent.ros.record import Recorder
    from dynevent.ros.spinning import Session
    from dynevent.wire.names import status_topic

    class Times:  # rosbags' writer, as far as the recorder uses it: the time each message is written at
        def __init__(self) -> None:
            self.times: list[int] = []
            self.sent: list[int | None] = []
            self.numbers: list[int] = []

        def add_connection(self, topic: str, msgtype: str, **details: Any) -> str:
            return topic

        def write_sent(self, connection: str, time: int, sent: int | None, data: bytes, number: int) -> None:
            self.times.append(time)
            self.sent.append(sent)
            self.numbers.append(number)

    recording, robot = Session("dynevent_recorder", own_context=True), Session("tinyRobot1", own_context=True)
    try:
        writer = Times()
        recorder = Recorder(recording.node, writer, lambda fleet, name: True, say=lambda line: None)
        recorder.expect("tinyRobot", "tinyRobot1")
        publisher = robot.node.create_publisher(DynamicEventStatus, status_topic("tinyRobot", "tinyRobot1"),
                                                latched(10))  # fmt: skip
        subscription = recorder.topics["/" + status_topic("tinyRobot", "tinyRobot1")]
        deadline = time.monotonic() + 15
        while subscription.get_publisher_count() == 0 and time.monotonic() < deadline:
            time.sleep(0.05)
        assert subscription.get_publisher_count() == 1
        sent, published = [], []
        for seq in range(1, 6):  # the recorder's executor does not run yet: it has fallen behind
            before = time.time_ns()
            publisher.publish(DynamicEventStatus(dynamic_event_seq=seq, dynamic_state=1, status="standby"))
            sent.append(time.time_ns())
            published.append((before, sent[-1]))
            time.sleep(0.2)
        recording.start()  # and now takes all five at once
        while len(writer.times) < 5 and time.monotonic() < deadline:
            time.sleep(0.05)
        assert len(writer.times) == 5
        assert writer.times == sorted(writer.times)
        # at least 0.8 s between the first and the last sent; taken in a burst, they would be a few
        # milliseconds apart
        spread, sent_spread = writer.times[-1] - writer.times[0], sent[-1] - sent[0]
        assert spread > sent_spread / 2, (spread, sent_spread, writer.times)
        # and each with the time its publisher sent it (the bag's publish time: dynevent.bags.sent)
        assert all(
            before <= stamp <= after for (before, after), stamp in zip(published, writer.sent, strict=True)
        ), (published, writer.sent)
        # and its publisher's number for it, one by one (a gap would be a message lost for good)
        assert writer.numbers[0] > 0 and writer.numbers == list(
            range(writer.numbers[0], writer.numbers[0] + 5)
        )
    finally:
        recording.close()
        robot.close()
