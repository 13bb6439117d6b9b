"""The ROS tests' own graph: what one test made is gone from DDS before the next test begins.

rclpy's ``destroy_node`` leaves a node's action servers and clients alive, and they keep their node,
and ``shutdown`` keeps the context's DDS participant, until the garbage collector gets to them.  A
later test's client then met earlier tests' action servers under the same names, and now and then
missed its own server for good: ``wait_for_server`` returned False after its whole bound (measured:
6 of the first 76 iterations of ten clients each, 34 waits in 760, against none in 2,000 waits
once :meth:`Graph.close` destroys everything it made; docs/testing.md).
"""

from __future__ import annotations

import gc
from typing import Any

import pytest
from rclpy.action import ActionServer
from rmf_task_msgs.action import DynamicEvent
from ros_support import Graph, wait_for

STALE = "rmf/dynamic_event/command/graphTest/stale"
LIVE = "rmf/dynamic_event/command/graphTest/live"


def _server(name: str) -> Any:
    def execute(goal_handle: Any) -> Any:
        goal_handle.succeed()
        return DynamicEvent.Result()

    return lambda node: ActionServer(node, DynamicEvent, name, execute)


def test_a_closed_graph_leaves_no_entity_on_dds() -> None:
    gc.disable()  # the garbage collector would hide a leak now and then; the graph must not rely on it
    try:
        first = Graph()
        first.node("stale_server", _server(STALE))
        first.close()
        other = Graph()
        second = Graph()
        try:
            other.node("live_server", _server(LIVE))
            probe = second.node("probe")
            # the live server is another participant, as the stale one would be: once the probe counts
            # it, the participants of this process have met, and a stale server would be counted too
            wait_for(lambda: probe.count_publishers(f"/{LIVE}/_action/feedback") == 1, "the live server")
            assert probe.count_publishers(f"/{STALE}/_action/feedback") == 0
            assert "stale_server" not in probe.get_node_names()
        finally:
            second.close()
            other.close()
    finally:
        gc.enable()


def test_a_spinner_stops_between_waits_and_close_down_deletes_the_participant() -> None:
    """``dynevent send`` and ``serve`` end through :class:`~dynevent.ros.spinning.Spinner` and
    :func:`~dynevent.ros.spinning.close_down`: the spinning thread is out of rclpy before anything is
    destroyed, and the process's DDS participant is deleted before the interpreter's exit, where a
    participant left to Fast DDS's static destructors can hang the process (a CI run's ``send`` did)."""
    import threading

    import rclpy
    from rclpy._rclpy_pybind11 import InvalidHandle
    from rclpy.executors import SingleThreadedExecutor

    from dynevent.ros import DynamicEventClient
    from dynevent.ros.spinning import Spinner, close_down

    gc.disable()
    try:
        context = rclpy.Context()
        rclpy.init(context=context)
        node = rclpy.create_node("spun_client", context=context)
        DynamicEventClient(node, "graphTest", "spun")  # a timer, subscriptions and an action client
        executor = SingleThreadedExecutor(context=context)
        executor.add_node(node)
        spinner = Spinner(executor, "spinner-under-test")
        spinner.start()
        wait_for(lambda: any(t.name == "spinner-under-test" for t in threading.enumerate()), "spinning")
        assert spinner.stop(timeout=5) is True
        assert not any(t.name == "spinner-under-test" for t in threading.enumerate())
        watcher = Graph()
        try:
            probe = watcher.node("probe")
            wait_for(lambda: "spun_client" in probe.get_node_names(), "the spun client on the graph")
            close_down([node], context)
            wait_for(lambda: "spun_client" not in probe.get_node_names(), "the node gone")
            # the participant is the context's: destroyed, not left for the interpreter's exit
            with pytest.raises(InvalidHandle):
                context.ok()
        finally:
            watcher.close()
    finally:
        gc.enable()


def test_a_spinner_of_an_idle_node_waits_without_a_timeout_and_still_stops() -> None:
    """serve's lanes have no timer while idle: the spinning thread waits with no timeout (an idle fleet
    costs nothing), and a stop must still end it, through its wait condition, not a timeout."""
    import rclpy
    from rclpy.executors import SingleThreadedExecutor

    from dynevent.ros.spinning import Spinner, close_down

    context = rclpy.Context()
    rclpy.init(context=context)
    node = rclpy.create_node("idle_lane", context=context)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    waits: list[tuple[object, ...]] = []
    original = executor._spin_once_impl

    def counting(*args: object) -> None:
        waits.append(args)
        original(*args)

    executor._spin_once_impl = counting  # type: ignore[method-assign]
    spinner = Spinner(executor, "idle-spinner")
    spinner.start()
    try:
        wait_for(lambda: len(waits) == 1, "the first wait")
        __import__("threading").Event().wait(0.5)
        assert waits[0][0] is None  # no timeout on the wait
        assert len(waits) == 1  # and nothing woke it while idle
    finally:
        assert spinner.stop(timeout=2) is True  # woken by the stop, well within the bound
        close_down([node], context)


SESSIONS = """
import threading
import rclpy
from dynevent.errors import LocalError
from dynevent.ros.spinning import Session
first = Session("dynevent_first", ["--ros-args", "-r", "__ns:=/one"])
first.start()
print(first.node.get_namespace(), [t.name for t in threading.enumerate() if t.name.startswith("dynevent")])
try:
    Session("dynevent_refused", ["--ros-args", "-r", "__ns:=/two"])
except LocalError as exc:
    print("refused:", exc)
lane = Session("dynevent_lane")  # the default context already up: shared, not started again
print(lane.node.get_namespace(), lane.context is None)
lane.close()
first.close()
second = Session("dynevent_second", ["--ros-args", "-r", "__ns:=/three"])  # a new default context
second.start()
print(second.node.get_namespace(), rclpy.ok())
second.close()
print("ok" if not rclpy.ok() else "still up")
"""


def test_sessions_start_the_default_context_once_and_a_closed_one_is_started_anew() -> None:
    """A Session on the default context starts it with its ROS arguments unless it is up; then it
    shares it, and refuses arguments of its own (they would be lost without a word).  Once closed, the
    default context is retired: the process's next Session starts a new one (rclpy's own default
    would be the destroyed context, which no init can use again)."""
    import subprocess
    import sys

    from ros_support import child_env

    done = subprocess.run([sys.executable, "-c", SESSIONS], capture_output=True, text=True, timeout=60,
                          env=child_env(), check=False)  # fmt: skip
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[0] == "/one ['dynevent-first']", lines
    assert lines[1] == "refused: --ros-args -r __ns:=/two: ROS is already started in this process, with " \
        "arguments of its own", lines  # fmt: skip
    assert lines[2:] == ["/one True", "/three True", "ok"], lines
