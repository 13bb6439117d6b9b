"""rosbag2 recordings of one robot's conversation, written by rosbags' own writer (not dynevent's code),
in both storage formats: what the tests of the bag reader (tests/bags) and of ``dynevent check``
(tests/tools/check) judge.

- :class:`Conversation`: a robot's messages as a recording holds them, built message by message, and
  written as a bag (:meth:`Conversation.write`);
- :func:`clean_run`, :func:`partial_clean_run`: whole runs a correct server may be recorded doing,
  with introspection and from the topics alone (:func:`topics_alone`);
- :func:`check_command`: ``dynevent check`` run as a process of its own.

(The messages are built from the type store the reader uses; tests/ros/test_ros_bags.py writes them
with ROS's own serialisation instead.)
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
from rosbags.rosbag2 import StoragePlugin, Writer

from dynevent.bags.reader import _definitions, _stored_name, typestore
from dynevent.bags.sent import open_writer

STORE = typestore()
DEFINITIONS = _definitions()
#: A type hash for the topics' metadata (the reader does not use it).
UNHASHED = "RIHS01_" + "0" * 64
FLEET, ROBOT = "tinyRobot", "r1"
ACTION = f"/rmf/dynamic_event/command/{FLEET}/{ROBOT}"
STATUS_TOPIC = f"/rmf/dynamic_event/status/{FLEET}/{ROBOT}"
BEGIN_TOPIC = f"/rmf/dynamic_event/begin/{FLEET}/{ROBOT}"
SECOND = 10**9
T0 = 1_700_000_000 * SECOND


def ros_type(name: str) -> Any:
    return STORE.types[name]


def ros_time(ns: int) -> Any:
    return ros_type("builtin_interfaces/msg/Time")(sec=ns // SECOND, nanosec=ns % SECOND)


def ros_uuid(n: int) -> Any:
    return ros_type("unique_identifier_msgs/msg/UUID")(uuid=np.array([n] * 16, dtype=np.uint8))


class Conversation:
    """A robot's messages as a rosbag2 recording holds them: (topic, type, bag time, message)."""

    def __init__(self) -> None:
        self.messages: list[tuple[str, str, int, Any]] = []
        self.now = T0
        self.calls = 0  # get_result calls
        self.sent: dict[int, int] = {}  # id of a message: when its publisher sent it (the bag's publish time)
        self.numbers: dict[int, int] = {}  # id of a message: its publisher's number for it

    def at(self, topic: str, msgtype: str, message: Any) -> Conversation:
        self.now += SECOND // 10
        self.messages.append((topic, msgtype, self.now, message))
        return self

    def status(self, seq: int, phase: int, status: str, event_id: int) -> Conversation:
        message = ros_type("rmf_task_msgs/msg/DynamicEventStatus")(
            dynamic_event_seq=seq, dynamic_state=phase, status=status, id=event_id, time=ros_time(self.now)
        )
        return self.at(STATUS_TOPIC, "rmf_task_msgs/msg/DynamicEventStatus", message)

    def begin(self, seq: int = 1, topic: str = BEGIN_TOPIC) -> Conversation:
        message = ros_type("rmf_task_msgs/msg/DynamicEventDescription")(
            fleet=FLEET, robot=ROBOT, dynamic_event_seq=seq, description="{}", start_time=ros_time(self.now)
        )
        return self.at(topic, "rmf_task_msgs/msg/DynamicEventDescription", message)

    def _event(
        self, service: str, kind: int, call: int, request: Any = None, response: Any = None
    ) -> Conversation:
        """A service event as ROS 2 introspection records it: a request event carries the request, a
        response event the response alone, the two paired by the client's GID and ``call``."""
        name = {"send_goal": "DynamicEvent_SendGoal", "get_result": "DynamicEvent_GetResult"}[service]
        info = ros_type("service_msgs/msg/ServiceEventInfo")(
            event_type=kind,
            stamp=ros_time(self.now),
            client_gid=np.zeros(16, dtype=np.uint8),
            sequence_number=call,
        )
        msgtype = f"rmf_task_msgs/action/{name}_Event"
        event = ros_type(msgtype)(
            info=info,
            request=[] if request is None else [request],
            response=[] if response is None else [response],
        )
        return self.at(f"{ACTION}/_action/{service}/_service_event", msgtype, event)

    def goal(
        self, n: int, *, accepted: bool = True, seq: int = 1, event_type: int = 1, goal_id: int = 0
    ) -> Conversation:
        goal = ros_type("rmf_task_msgs/action/DynamicEvent_Goal")(
            dynamic_event_seq=seq, event_type=event_type, category="go_to_place" if event_type == 1 else "",
            description='"pantry"' if event_type == 1 else "", id=goal_id, stubborn_period=0.0,
        )  # fmt: skip
        request = ros_type("rmf_task_msgs/action/DynamicEvent_SendGoal_Request")(
            goal_id=ros_uuid(n), goal=goal
        )
        response = ros_type("rmf_task_msgs/action/DynamicEvent_SendGoal_Response")(
            accepted=accepted, stamp=ros_time(0)
        )
        self._event("send_goal", 1, n, request=request)
        return self._event("send_goal", 2, n, response=response)

    def feedback(self, n: int, status: str, event_id: int, logs: tuple[int, ...] = ()) -> Conversation:
        entries = [
            ros_type("rmf_task_msgs/msg/LogEntry")(
                seq=seq,
                tier="info",
                unix_millis_time=(self.now + SECOND // 10) // 1_000_000,
                text="a log line",
            )  # stamped when the message is, as the server stamps it
            for seq in logs
        ]
        feedback = ros_type("rmf_task_msgs/action/DynamicEvent_Feedback")(
            status=status, id=event_id, logs=entries
        )
        message = ros_type("rmf_task_msgs/action/DynamicEvent_FeedbackMessage")(
            goal_id=ros_uuid(n), feedback=feedback
        )
        return self.at(
            f"{ACTION}/_action/feedback", "rmf_task_msgs/action/DynamicEvent_FeedbackMessage", message
        )

    def goal_statuses(self, *goals: tuple[int, int]) -> Conversation:
        """The action's goal status array: (goal, action_msgs/GoalStatus status) for each goal it holds."""
        items = [
            ros_type("action_msgs/msg/GoalStatus")(
                goal_info=ros_type("action_msgs/msg/GoalInfo")(goal_id=ros_uuid(n), stamp=ros_time(T0)),
                status=code,
            )
            for n, code in goals
        ]
        message = ros_type("action_msgs/msg/GoalStatusArray")(status_list=items)
        return self.at(f"{ACTION}/_action/status", "action_msgs/msg/GoalStatusArray", message)

    def ask(self, n: int) -> Conversation:
        """A client asks for goal ``n``'s answer (the server holds the call until the answer)."""
        request = ros_type("rmf_task_msgs/action/DynamicEvent_GetResult_Request")(goal_id=ros_uuid(n))
        self.calls += 1
        return self._event("get_result", 1, self.calls, request=request)

    def result(self, n: int, goal_status: int, status: str, event_id: int) -> Conversation:
        request = ros_type("rmf_task_msgs/action/DynamicEvent_GetResult_Request")(goal_id=ros_uuid(n))
        result = ros_type("rmf_task_msgs/action/DynamicEvent_Result")(
            execution_failure="", status=status, id=event_id
        )
        response = ros_type("rmf_task_msgs/action/DynamicEvent_GetResult_Response")(
            status=goal_status, result=result
        )
        self.calls += 1
        self._event("get_result", 1, self.calls, request=request)
        return self._event("get_result", 2, self.calls, response=response)

    def sent_at(self, time: int) -> Conversation:
        """The last message was sent at ``time`` (ns): an MCAP bag holds it as the publish time."""
        self.sent[id(self.messages[-1][3])] = time
        return self

    def numbered(self, number: int) -> Conversation:
        """The last message was its publisher's ``number``-th: an MCAP bag holds it as the sequence."""
        self.numbers[id(self.messages[-1][3])] = number
        return self

    def write(self, path: Path, storage: StoragePlugin) -> Path:
        """The bag: MCAP storage through the recorder's writer (publish times kept), SQLite through
        rosbags' own."""
        mcap = storage == StoragePlugin.MCAP
        writer = open_writer(path) if mcap else Writer(path, version=9, storage_plugin=storage)
        with writer:
            connections: dict[str, Any] = {}
            for topic, msgtype, time, message in self.messages:
                if topic not in connections:
                    # the definition as rosbag2 keeps it (rosbags generates one for "msg" types only)
                    text = DEFINITIONS.get(msgtype, "")
                    connections[topic] = writer.add_connection(topic, msgtype, msgdef=text, rihs01=UNHASHED)
                data = STORE.serialize_cdr(message, _stored_name(STORE, msgtype))
                if mcap:
                    number = self.numbers.get(id(message), 0)
                    writer.write_sent(connections[topic], time, self.sent.get(id(message)), data, number)
                else:
                    writer.write(connections[topic], time, data)
        return path

    def cancel(self, n: int, kind: int, clock: int = 0, *, return_code: int = 0) -> Conversation:
        """An action-level cancel of goal ``n`` as a client's introspection records it (``kind`` 0: the
        request sent, 3: the response received) or the server's (1: the request received, 2: the
        response sent), stamped by a clock ``clock`` ns ahead; the response accepts it
        (``return_code`` 0) or refuses it with that code (1 rejected, 3 the goal terminated)."""
        info = ros_type("service_msgs/msg/ServiceEventInfo")(
            event_type=kind, stamp=ros_time(self.now + SECOND // 10 + clock),
            client_gid=np.ones(16, dtype=np.uint8), sequence_number=1,
        )  # fmt: skip
        goal_info = ros_type("action_msgs/msg/GoalInfo")(goal_id=ros_uuid(n), stamp=ros_time(0))
        request = ros_type("action_msgs/srv/msg/CancelGoal_Request")(goal_info=goal_info)
        response = ros_type("action_msgs/srv/msg/CancelGoal_Response")(
            return_code=return_code, goals_canceling=[] if return_code else [goal_info]
        )
        event = ros_type("action_msgs/srv/msg/CancelGoal_Event")(
            info=info,
            request=[request] if kind in (0, 1) else [],
            response=[response] if kind in (2, 3) else [],
        )
        return self.at(
            f"{ACTION}/_action/cancel_goal/_service_event", "action_msgs/srv/CancelGoal_Event", event
        )


SUCCEEDED, ABORTED = 4, 6


def clean_run(between: Any = None) -> Conversation:
    """A run: begin, a NEXT that runs its child to the end, FINISHED; ``between(run)`` adds messages
    after the NEXT's answer."""
    run = Conversation().begin().status(1, 1, "standby", 0)
    run.goal(1, goal_id=1).feedback(1, "underway", 1).status(1, 2, "underway", 1)
    run.result(1, SUCCEEDED, "completed", 1)
    if between is not None:
        between(run)
    run.status(1, 1, "standby", 1)
    run.goal(2, event_type=3).result(2, SUCCEEDED, "completed", 0).status(1, 0, "uninitialized", 0)
    return run


STORAGES = [StoragePlugin.MCAP, StoragePlugin.SQLITE3]


ACCEPTED, EXECUTING, CANCELING, CANCELED = 1, 2, 3, 5


def topics_alone(run: Conversation) -> Conversation:
    """The conversation as a recording without introspection holds it: its topics alone."""
    run.messages = [item for item in run.messages if "_service_event" not in item[0]]
    return run


def partial_clean_run() -> Conversation:
    """Two runs as their topics show them: a NEXT whose child logs and ends, with the action's goal
    statuses; a run ended by FINISHED; a second run's NEXT cancelled through the action."""
    run = Conversation().begin().status(1, 1, "standby", 0)
    run.goal(1, goal_id=1).goal_statuses((1, EXECUTING)).feedback(1, "underway", 1, logs=(0,))
    run.status(1, 2, "underway", 1).feedback(1, "completed", 1, logs=(1, 2)).status(1, 2, "completed", 1)
    run.goal_statuses((1, SUCCEEDED)).status(1, 1, "standby", 1)
    run.goal_statuses((1, SUCCEEDED), (2, EXECUTING)).goal_statuses((1, SUCCEEDED), (2, SUCCEEDED))
    run.status(1, 0, "uninitialized", 0).begin(2).status(2, 1, "standby", 7)
    run.goal_statuses((3, EXECUTING)).feedback(3, "underway", 8, logs=(5,)).status(2, 2, "underway", 8)
    run.goal_statuses((3, CANCELED)).status(2, 1, "standby", 8)
    run.now += 5 * SECOND  # the robot waits
    return run.status(2, 1, "underway", 8)  # a stubborn wait, say: the run's id stays


def check_command(*args: str) -> subprocess.CompletedProcess[str]:
    """``python -m dynevent check ARGS``, in a process of its own (a minute at most)."""
    command = [sys.executable, "-m", "dynevent", "check", *args]
    return subprocess.run(command, check=False, capture_output=True, text=True, timeout=60)
