"""A goal's round trip through dynevent's ROS binding, against a bare rclpy action server.

Two servers, each in a process of its own, serve the same action type
(``rmf_task_msgs/action/DynamicEvent``) for one robot:

- ``dynevent``: :class:`dynevent.ros.DynamicEventServer`, whose adapter
  finishes each child at once (the start feeds back ``underway``, R6.4: one
  feedback, as the peers send; the binding and the machine, without
  ``dynevent serve``'s simulation timers);
- ``peer``: a bare rclpy ``ActionServer`` that accepts, executes, publishes one
  feedback and succeeds: the least a server doing the same exchange does;
- ``peer_status``: the same, plus the two status messages the protocol
  requires of every goal (RUNNING when it starts, WAITING when it ends), which
  dynevent publishes and the bare peer does not;
- ``dynevent_rmf_ros2``: dynevent's server in ``rmf_ros2`` mode, as ``dynevent
  serve --compatibility rmf_ros2`` configures it, with the same children;
- with ``--adapter FLEET/ROBOT --adapter-pid PID --place PLACE``, a live
  server too: Open-RMF's own fleet adapter (lab/rmf_ros2/), sent NEXTs to the
  place its robot stands at, so that each child ends at once (the adapter
  plans, finds the robot there, and completes).

One client (a plain rclpy ``ActionClient``, the same for all) sends NEXT
goals one after another and times each from the send to the result, with the
feedback in between.  The servers are measured in alternating batches in one
run, so that they share the machine's noise, and replaced by fresh processes
every ``--per-server`` goals, so that the goals rclpy's action servers keep
(each for 10 s after its end, all of them in every status message) stay as few
as a dynamic event's, whose goals come seconds apart.  Reported: the median
and p90 of each, the medians of when the goal response, the first feedback and
the result reached the client, and dynevent's cost on top of rclpy's as a
fraction of the bare round trip.  Needs a ROS 2 environment with
``rmf_task_msgs``.

    python bench/ros_roundtrip.py [--goals N] [--quick] [--write]
    python bench/ros_roundtrip.py --adapter tinyRobot/tinyRobot1 --adapter-pid PID --place hall

``--write`` records the result as the ``ros-roundtrip`` section of bench/results.md.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import statistics
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # run as a script: make `bench` importable
    sys.path.insert(0, str(ROOT))

from bench import results  # noqa: E402

SERVER = r"""
import sys, threading, signal
import rclpy
from rclpy.action import ActionServer, GoalResponse, CancelResponse
from rclpy.executors import MultiThreadedExecutor
from rmf_task_msgs.action import DynamicEvent

kind, fleet, robot = sys.argv[1:4]
rclpy.init()
node = rclpy.create_node("bench_server_" + kind)
if kind in ("dynevent", "dynevent_rmf_ros2"):
    from dynevent.server.machine import ServerConfig, any_description
    from dynevent.ros import DynamicEventServer

    class Children:
        def start(self, execution):
            # the start already fed back "underway" (R6.4): one feedback, as the peers send
            execution.finished()
        def cancel(self, execution): execution.finished()
        def kill(self, execution): execution.finished()
        def interrupt(self, execution): pass
        def resume(self, execution): pass

    categories = {"go_to_place": any_description}
    config = ServerConfig(categories=categories)
    if kind == "dynevent_rmf_ros2":
        config = ServerConfig.rmf_ros2(categories)
    server = DynamicEventServer(node, fleet, robot, config, Children())
    server.begin("{}", 0)
if kind in ("peer", "peer_status"):
    status = None
    if kind == "peer_status":
        from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
        from rmf_task_msgs.msg import DynamicEventStatus
        latched = QoSProfile(
            depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
        )
        status = node.create_publisher(
            DynamicEventStatus, f"rmf/dynamic_event/status/{fleet}/{robot}", latched
        )

    def publish_status(state, text, event_id):
        if status is not None:
            message = DynamicEventStatus(dynamic_event_seq=1, dynamic_state=state, status=text, id=event_id)
            message.time = node.get_clock().now().to_msg()
            status.publish(message)

    def execute(handle):
        publish_status(2, "underway", handle.request.id)
        handle.publish_feedback(DynamicEvent.Feedback(status="underway", id=handle.request.id))
        handle.succeed()
        publish_status(1, "standby", handle.request.id)
        return DynamicEvent.Result(status="completed", id=handle.request.id)
    ActionServer(
        node, DynamicEvent, f"rmf/dynamic_event/command/{fleet}/{robot}", execute_callback=execute,
        goal_callback=lambda goal: GoalResponse.ACCEPT, cancel_callback=lambda handle: CancelResponse.ACCEPT,
    )
executor = MultiThreadedExecutor(num_threads=2)
executor.add_node(node)
print("ready", flush=True)
stop = threading.Event()
signal.signal(signal.SIGTERM, lambda *_: stop.set())
threading.Thread(target=executor.spin, daemon=True).start()
stop.wait(600)
"""


#: The parts of a goal's exchange the client times, from the send: the goal response, the first
#: feedback and the result (medians in the table; the round trip ends at the later of the last two).
PARTS = ("response", "feedback", "result")

#: Goals each server process serves before fresh ones replace them.  rclpy's action server keeps
#: every goal for 10 s after its end (``result_timeout``) and publishes all it keeps in each status
#: message, which every client converts: at hundreds of goals a second, the goals kept would make
#: rclpy's own work grow with the run's length and bury what each server adds.  A dynamic event's
#: goals come seconds apart, so that a server keeps a few.
PER_SERVER = 50

#: Goals each client sends before its timed ones (after each start of fresh servers).
WARM_UP = 10

#: The servers measured: dynevent, the bare peer, and the peer that also publishes the two status
#: messages the protocol requires of every goal (RUNNING at its start, WAITING at its end).
KINDS = ("dynevent", "dynevent_rmf_ros2", "peer", "peer_status")


class Client:
    """A plain rclpy action client for one robot; times goals from send to result."""

    def __init__(
        self, node: Any, fleet: str, robot: str, description: str = '"a"', live: bool = False
    ) -> None:
        from rclpy.action import ActionClient
        from rmf_task_msgs.action import DynamicEvent

        self.goal_type = DynamicEvent.Goal
        self.name = f"{fleet}/{robot}"
        self.description = description
        self.seq = 1
        self.action = ActionClient(node, DynamicEvent, f"rmf/dynamic_event/command/{fleet}/{robot}")
        if not self.action.wait_for_server(timeout_sec=20):
            raise SystemExit(f"no server for {fleet}/{robot}")
        if live:  # a live server's run: its seq from the status topic
            from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
            from rmf_task_msgs.msg import DynamicEventStatus

            latched = QoSProfile(
                depth=1, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.TRANSIENT_LOCAL
            )
            heard = threading.Event()

            def on_status(message: Any) -> None:
                self.seq = message.dynamic_event_seq
                heard.set()

            topic = f"rmf/dynamic_event/status/{fleet}/{robot}"
            self.subscription = node.create_subscription(DynamicEventStatus, topic, on_status, latched)
            if not heard.wait(20):
                raise SystemExit(f"no status from {fleet}/{robot}")

    def round_trip(self, goal_id: int, timeout: float = 10.0) -> tuple[float, int, str, dict[str, float]]:
        """Seconds from send until both the result and a feedback are in; the feedback count, the
        status, and when each part arrived (seconds after the send: ``response``, ``feedback``,
        ``result``).

        Feedback and result travel on different topics, so either may arrive first.
        """
        answered = threading.Event()
        fed = threading.Event()
        feedback: list[Any] = []
        result: list[Any] = []
        marks: dict[str, float] = {}

        def on_feedback(message: Any) -> None:
            marks.setdefault("feedback", time.perf_counter() - started)
            feedback.append(message)
            fed.set()

        def on_result(future: Any) -> None:
            marks["result"] = time.perf_counter() - started
            result.append(future.result())
            answered.set()

        def on_response(future: Any) -> None:
            handle = future.result()
            marks["response"] = time.perf_counter() - started
            if not handle.accepted:
                fed.set()
                answered.set()
                return
            handle.get_result_async().add_done_callback(on_result)

        goal = self.goal_type(
            dynamic_event_seq=self.seq,
            event_type=1,
            category="go_to_place",
            description=self.description,
            id=0,
        )
        started = time.perf_counter()
        self.action.send_goal_async(goal, feedback_callback=on_feedback).add_done_callback(on_response)
        deadline = started + timeout
        if not (answered.wait(timeout) and fed.wait(max(deadline - time.perf_counter(), 0.0))):
            got = f"{'an answer' if answered.is_set() else 'no answer'} and {len(feedback)} feedback"
            raise SystemExit(f"{self.name}: goal {goal_id}: {got} within {timeout} s")
        elapsed = time.perf_counter() - started
        status = result[0].result.status if result else "rejected"
        return elapsed, len(feedback), status, marks


def _cpu_seconds(pid: int) -> float:
    """A process's user and system CPU time so far (Linux)."""
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")


def _percentile(values: list[float], fraction: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(fraction * len(ordered)))]


def _start_servers(suffix: str) -> dict[str, subprocess.Popen[str]]:
    """One process per server kind, started at once, each serving robot ``<kind>_<suffix>``."""
    servers = {
        kind: subprocess.Popen(
            [sys.executable, "-c", SERVER, kind, "bench", f"{kind}_{suffix}"],
            stdout=subprocess.PIPE,
            text=True,
        )
        for kind in KINDS
    }
    for kind, process in servers.items():
        assert process.stdout is not None
        if process.stdout.readline().strip() != "ready":
            _stop_servers(servers)
            raise SystemExit(f"the {kind} server did not start")
    return servers


def _stop_servers(servers: dict[str, subprocess.Popen[str]]) -> None:
    for process in servers.values():
        process.terminate()
    for process in servers.values():
        process.wait(timeout=10)


def _warm_up(clients: dict[str, Client]) -> None:
    """:data:`WARM_UP` whole exchanges with each server.  A client's feedback topic may match the
    server's a moment after ``wait_for_server`` (which waits for the action's services only), so that
    the first goals' feedback may be lost: those goals are sent again."""
    for client in clients.values():
        whole = 0
        for index in range(10 * WARM_UP):
            try:
                client.round_trip(index, timeout=2.0)
            except SystemExit:
                continue
            whole += 1
            if whole == WARM_UP:
                break
        else:
            raise SystemExit(f"{client.name}: fewer than {WARM_UP} whole exchanges in {10 * WARM_UP} goals")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--goals", type=int, default=400, help="goals per server (default 400)")
    parser.add_argument("--batch", type=int, default=10, help="goals per batch, alternating servers")
    parser.add_argument(
        "--per-server",
        type=int,
        default=PER_SERVER,
        help=f"goals each server process serves before a fresh one replaces it (default {PER_SERVER})",
    )
    parser.add_argument("--quick", action="store_true", help="40 goals each: a smoke run")
    parser.add_argument("--write", action="store_true", help="record the result in bench/results.md")
    parser.add_argument(
        "--adapter", metavar="FLEET/ROBOT", help="also a live server: Open-RMF's fleet adapter"
    )
    parser.add_argument("--adapter-pid", type=int, help="the live server's process, for its CPU")
    parser.add_argument("--place", help="where the live server's robot stands (each child then ends at once)")
    args = parser.parse_args(argv)
    if args.adapter and (args.adapter_pid is None or not args.place or "/" not in args.adapter):
        parser.error("--adapter FLEET/ROBOT needs --adapter-pid and --place")
    goals = 40 if args.quick else args.goals
    if not args.adapter:  # a live server is found in the domain the environment names
        os.environ.setdefault("ROS_DOMAIN_ID", str(random.randint(150, 200)))
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"

    import rclpy
    from rclpy.executors import MultiThreadedExecutor

    rclpy.init()
    node = rclpy.create_node("bench_client")
    executor = MultiThreadedExecutor(num_threads=2)
    executor.add_node(node)
    threading.Thread(target=executor.spin, daemon=True).start()
    names = [*KINDS, *(["rmf_ros2 adapter"] if args.adapter else [])]
    times: dict[str, list[float]] = {kind: [] for kind in names}
    arrived: dict[str, dict[str, list[float]]] = {kind: {part: [] for part in PARTS} for kind in names}
    cpu: dict[str, float] = {kind: 0.0 for kind in names}
    live: dict[str, Client] = {}
    pids: dict[str, int] = {}
    try:
        if args.adapter:
            fleet, robot = args.adapter.split("/", 1)
            place = json.dumps({"one_of": [args.place]})
            live["rmf_ros2 adapter"] = Client(node, fleet, robot, description=place, live=True)
            pids["rmf_ros2 adapter"] = args.adapter_pid
            _warm_up(live)
        sent = 0
        while sent < goals:  # a round: fresh servers, each serving --per-server goals
            servers = _start_servers(f"round{sent}")
            clients = {kind: Client(node, "bench", f"{kind}_round{sent}") for kind in servers}
            try:
                pids.update({kind: process.pid for kind, process in servers.items()})
                _warm_up(clients)
                clients.update(live)
                end = min(goals, sent + args.per_server)
                while sent < end:
                    batch = min(args.batch, end - sent)
                    for kind, client in clients.items():
                        before = _cpu_seconds(pids[kind])
                        for index in range(batch):
                            elapsed, feedback, status, marks = client.round_trip(sent + index)
                            if status != "completed" or feedback < 1:
                                raise SystemExit(f"{kind}: goal ended {status!r} with {feedback} feedback")
                            times[kind].append(elapsed)
                            for part in PARTS:
                                arrived[kind][part].append(marks[part])
                        cpu[kind] += _cpu_seconds(pids[kind]) - before
                    sent += batch
            finally:
                for kind in servers:
                    clients[kind].action.destroy()
                _stop_servers(servers)
    finally:
        executor.shutdown(timeout_sec=2)
        rclpy.try_shutdown()
    medians = {kind: statistics.median(values) for kind, values in times.items()}
    extra = (medians["dynevent"] - medians["peer"]) / medians["peer"]
    extra_status = (medians["dynevent"] - medians["peer_status"]) / medians["peer_status"]
    rows = [
        f"| {kind} | {len(values)} | {medians[kind] * 1e3:.2f} ms | {_percentile(values, 0.9) * 1e3:.2f} ms "
        f"| {cpu[kind] / len(values) * 1e3:.2f} ms | "
        + " | ".join(f"{statistics.median(arrived[kind][part]) * 1e3:.2f} ms" for part in PARTS)
        + " |"
        for kind, values in times.items()
    ]
    lines = [
        "## ROS 2: a goal's round trip (bench/ros_roundtrip.py)",
        "",
        "NEXT sent -> accepted -> one feedback -> result, one goal at a time, through dynevent's",
        "ROS binding and through a bare rclpy action server doing the same exchange, in alternating",
        f"batches of {args.batch} in one run{' (quick mode)' if args.quick else ''}, each server process",
        f"replaced by a fresh one every {args.per_server} goals (after {WARM_UP} untimed ones).",
        "",
        *results.machine_description(("dynevent", "rclpy")),
        "",
        "| server | goals | median | p90 | server CPU per goal | response at | feedback at | result at |",
        "|---|---|---|---|---|---|---|---|",
        *rows,
        "",
        "Response, feedback and result at: the medians of when each reached the client, after the send.",
        "",
        f"dynevent's cost on top of the bare round trip: **{extra:+.1%}** of it (target: within +5%);",
        f"on top of the peer that also publishes the two status messages: **{extra_status:+.1%}**.",
    ]
    if args.adapter:
        ratio = medians["rmf_ros2 adapter"] / medians["peer"]
        lines.append(
            f"Open-RMF's fleet adapter ({args.adapter}, its child a go_to_place to where the robot "
            f"stands): **{ratio:.1f}x** the bare round trip."
        )
    print("\n".join(lines))
    if args.write:
        results.write_section("ros-roundtrip-adapter" if args.adapter else "ros-roundtrip", lines)
        print(f"wrote {results.RESULTS}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
