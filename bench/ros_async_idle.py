"""What a client costs while it waits for a child to end: CPU seconds per wall second.

``dynevent serve`` runs one robot whose children take ``--child`` seconds.  In this process, one
after the other, each client sends a NEXT and waits for its answer, and the process's CPU time over
that wait is divided by the wall time:

- ``async``: :class:`dynevent.ros.AsyncRobotClient`, awaited from ``asyncio.run``;
- ``robot``: :class:`dynevent.ros.RobotClient`, ``GoalRun.wait`` from the main thread;
- ``peer``: a plain rclpy ``ActionClient`` on a node a ``SingleThreadedExecutor`` spins in a thread,
  the main thread waiting on a ``threading.Event`` set by the result callback (the least a client
  doing the same costs).

Needs a ROS 2 environment with ``rmf_task_msgs``::

    python bench/ros_async_idle.py [--child SECONDS] [--write]

``--write`` records the result as the ``ros-async-idle`` section of bench/results.md.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from bench import results  # noqa: E402

ROBOT = "idleRobot"


def _measure(wait: Callable[[], object]) -> float:
    """CPU seconds per wall second of the process while ``wait()`` runs."""
    cpu, wall = time.process_time(), time.monotonic()
    wait()
    return (time.process_time() - cpu) / (time.monotonic() - wall)


def _async() -> float:
    from dynevent.ros import AsyncRobotClient

    async def run() -> float:
        async with AsyncRobotClient("tinyRobot", ROBOT, node_name="bench_async") as robot:
            await robot.ready(15.0)
            loop = asyncio.get_running_loop()
            cpu, wall = time.process_time(), loop.time()
            await robot.next("go_to_place", '"pantry"')
            return (time.process_time() - cpu) / (loop.time() - wall)

    return asyncio.run(run())


def _robot() -> float:
    from dynevent.ros import RobotClient

    with RobotClient("tinyRobot", ROBOT, node_name="bench_robot") as robot:
        robot.ready(15.0)
        return _measure(lambda: robot.next("go_to_place", '"pantry"').wait(120.0))


def _idle_async(count: int, seconds: float, *, on_hub: bool = False) -> float:
    """``count`` AsyncRobotClients, each ready and holding no goal, for ``seconds``: CPU / wall.  Each
    with a context of its own, or ``on_hub``, all on one :class:`~dynevent.ros.RobotClients` hub
    (docs/ros.md's way for many robots in one process)."""
    from dynevent.ros import AsyncRobotClient, RobotClients

    async def run(hub: RobotClients | None) -> float:
        clients = [
            AsyncRobotClient("tinyRobot", ROBOT, node_name=f"bench_idle_{n}", hub=hub) for n in range(count)
        ]
        for client in clients:
            await client.__aenter__()
        try:
            await asyncio.gather(*(client.ready(30.0) for client in clients))
            cpu, wall = time.process_time(), time.monotonic()
            await asyncio.sleep(seconds)
            return (time.process_time() - cpu) / (time.monotonic() - wall)
        finally:
            for client in clients:
                await client.__aexit__(None, None, None)

    if not on_hub:
        return asyncio.run(run(None))
    with RobotClients(node_name="bench_idle_hub") as hub:
        return asyncio.run(run(hub))


def _idle_peer(count: int, seconds: float) -> float:
    """``count`` bare rclpy clients, each what an AsyncRobotClient holds (a context, a node with the
    status subscription and the action client, an executor spinning it in a thread), idle."""
    import rclpy
    from rclpy.action import ActionClient
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from rmf_task_msgs.action import DynamicEvent
    from rmf_task_msgs.msg import DynamicEventStatus

    latched = QoSProfile(
        depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
    )
    made = []
    for number in range(count):
        context = rclpy.Context()
        rclpy.init(context=context)
        node = rclpy.create_node(f"bench_idle_peer_{number}", context=context)
        node.create_subscription(
            DynamicEventStatus, f"rmf/dynamic_event/status/tinyRobot/{ROBOT}", lambda _: None, latched
        )
        ActionClient(node, DynamicEvent, f"rmf/dynamic_event/command/tinyRobot/{ROBOT}")
        executor = SingleThreadedExecutor(context=context)
        executor.add_node(node)
        threading.Thread(target=executor.spin, daemon=True).start()
        made.append((context, executor, node))
    try:
        time.sleep(min(seconds, 5.0))  # discovery settles, as the clients' ready() waits for it
        return _measure(lambda: time.sleep(seconds))
    finally:
        for context, executor, node in made:
            executor.shutdown(timeout_sec=1)
            node.destroy_node()
            rclpy.try_shutdown(context=context)


def _peer() -> float:
    import rclpy
    from rclpy.action import ActionClient
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
    from rmf_task_msgs.action import DynamicEvent
    from rmf_task_msgs.msg import DynamicEventStatus

    context = rclpy.Context()
    rclpy.init(context=context)
    node = rclpy.create_node("bench_peer", context=context)
    status: list[DynamicEventStatus] = []
    latched = QoSProfile(
        depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
    )
    node.create_subscription(
        DynamicEventStatus, f"rmf/dynamic_event/status/tinyRobot/{ROBOT}", status.append, latched
    )
    client = ActionClient(node, DynamicEvent, f"rmf/dynamic_event/command/tinyRobot/{ROBOT}")
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    thread = threading.Thread(target=executor.spin, daemon=True)
    thread.start()
    try:
        client.wait_for_server(timeout_sec=15.0)
        deadline = time.monotonic() + 15
        while not (status and status[-1].dynamic_state == 1) and time.monotonic() < deadline:
            time.sleep(0.05)
        last = status[-1]
        goal = DynamicEvent.Goal(
            dynamic_event_seq=last.dynamic_event_seq, event_type=1, category="go_to_place",
            description='"pantry"', id=last.id + 1,
        )  # fmt: skip
        done = threading.Event()

        def accepted(future: object) -> None:
            handle = future.result()  # type: ignore[attr-defined]
            handle.get_result_async().add_done_callback(lambda _: done.set())

        def send() -> None:
            client.send_goal_async(goal).add_done_callback(accepted)
            done.wait(120.0)

        return _measure(send)
    finally:
        executor.shutdown(timeout_sec=1)
        client.destroy()
        node.destroy_node()
        rclpy.try_shutdown(context=context)


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--child", type=float, default=5.0, help="how long each child takes (default 5 s)")
    parser.add_argument("--write", action="store_true", help="record the result in bench/results.md")
    parser.add_argument(
        "--idle",
        type=int,
        default=0,
        metavar="N",
        help="also N clients holding no goal, beside N bare rclpy clients (default none)",
    )
    parser.add_argument("--seconds", type=float, default=30.0, help="how long the idle ones are measured")
    options = parser.parse_args()
    config = Path(tempfile.mkdtemp()) / "fleet.json"
    config.write_text(json.dumps({"categories": {"go_to_place": {"duration": options.child}}}))
    serve = subprocess.Popen(
        [sys.executable, "-m", "dynevent", "serve", "--robot", ROBOT, "--config", str(config),
         "--rebegin", "0.2", "--no-judge"], stdout=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        assert serve.stdout is not None
        for line in serve.stdout:
            if line.startswith("serving "):
                break
        measured = {name: run() for name, run in (("async", _async), ("robot", _robot), ("peer", _peer))}
        if options.idle:
            idle = options.idle
            measured[f"{idle} idle async"] = _idle_async(idle, options.seconds)
            measured[f"{idle} idle async on one hub"] = _idle_async(idle, options.seconds, on_hub=True)
            measured[f"{idle} idle peers"] = _idle_peer(idle, options.seconds)
    finally:
        serve.terminate()
        serve.wait(timeout=30)
    lines = [
        "## ROS 2: a client waiting for a child's end (bench/ros_async_idle.py)",
        "",
        *results.machine_description(["dynevent"]),
        "",
        f"CPU seconds per wall second of the client's process while a NEXT's {options.child:g} s child runs"
        + (
            f"; and, idle for {options.seconds:g} s, {options.idle} clients holding no goal."
            if options.idle
            else "."
        ),
        "",
        "| client | CPU / wall |",
        "|---|---|",
        *(f"| {name} | {value:.4f} |" for name, value in measured.items()),
    ]
    print("\n".join(lines))
    if options.write:
        results.write_section("ros-async-idle", lines)
    return 0


if __name__ == "__main__":
    os.environ.setdefault("RMW_IMPLEMENTATION", "rmw_fastrtps_cpp")
    sys.exit(main())
