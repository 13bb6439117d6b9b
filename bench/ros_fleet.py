"""A fleet of simulated robots in one ``dynevent serve`` process, beside a bare rclpy peer.

Two servers, each in a process of its own, serve the same robots over real DDS on loopback:
``dynevent`` (``dynevent serve``) and ``peer`` (bench/peers/ros_bare_fleet.py: bare rclpy action
servers doing the same exchanges, with no protocol).  Two measurements:

- ``--idle 1,100,1000``: each server with that many robots and nothing to do; its CPU over
  ``--window`` seconds once it has started and settled, as a share of one core.
- load (the default): a load process (one node, a plain rclpy action client per robot) sends each
  robot a NEXT (id 0, the server numbers it) once a second, the next one as soon as the previous
  answered and its second is over, for ``--seconds``; a child takes ``--duration`` seconds with one
  progress report.  It checks that every goal got exactly one result and none failed, and reports
  goals per second, goals per second per core of the server's CPU, and the answer's overhead: the
  round trip (send to result) minus the child's own time, at the median and p99.

    python bench/ros_fleet.py [--robots 100] [--seconds 60] [--duration 0.2] [--write]
    python bench/ros_fleet.py --idle 1,100,1000 [--window 20] [--write]
    python bench/ros_fleet.py --robots 2000 --drive 200 --shards 1,2 [--write]
    python bench/ros_fleet.py --start 100,1000 [--write]

- ``--start 100,1000``: how long each server takes from its launch until it serves every robot
  (prints ``serving``): dynevent serve with its client judge (the default) and without it, beside
  the bare peer making the same entities (with the action servers' introspection, as the judge
  has), with rclpy's default DDS participant and with the one serve uses
  (dynevent.ros.participant: a participant that ignores its own endpoints).

``--write`` records the result as the ``ros-fleet`` or ``ros-fleet-idle`` section of
bench/results.md.
"""

from __future__ import annotations

import argparse
import json
import os
import random
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:  # run as a script: make `bench` importable
    sys.path.insert(0, str(ROOT))

from bench import results as recorded  # noqa: E402

TICKS = os.sysconf("SC_CLK_TCK")
PEER = str(ROOT / "bench" / "peers" / "ros_bare_fleet.py")
SERVERS = {
    "dynevent": lambda config: [sys.executable, "-m", "dynevent", "serve", "--config", str(config)],
    "peer": lambda config: [sys.executable, PEER, str(config)],
}
#: The servers whose start ``--start`` measures: serve as it runs (its judge on), serve without its
#: judge, and the bare peer making the same entities with rclpy's participant and with serve's.
STARTS = {
    "dynevent serve": SERVERS["dynevent"],
    "dynevent serve --no-judge": lambda config: [*SERVERS["dynevent"](config), "--no-judge"],
    "bare peer, rclpy's participant": lambda config: [sys.executable, PEER, str(config), "--introspection"],
    "bare peer, serve's participant": lambda config: [
        sys.executable,
        PEER,
        str(config),
        "--introspection",
        "--ignore-own",
    ],
}


def _cpu_seconds(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / TICKS  # utime + stime


class Server:
    """The server processes of ``robots`` robots (``shards`` of them, dynevent only), started and
    ready (each printed ``serving``); ``started`` is how long that took, in seconds."""

    def __init__(
        self,
        kind: str,
        robots: list[str],
        duration: float,
        shards: int = 1,
        start_timeout: float = 900,
        command: Any = None,
    ) -> None:
        folder = Path(tempfile.mkdtemp(prefix="dynevent-fleet-"))
        config = folder / "fleet.json"
        spec = {"duration": duration, "report_every": duration / 2}
        config.write_text(
            json.dumps(
                {"fleet": "benchFleet", "robots": robots, "rebegin": 0, "categories": {"go_to_place": spec}}
            )
        )
        began = time.monotonic()
        parts = [[]] if shards == 1 else [["--shard", f"{index}/{shards}"] for index in range(1, shards + 1)]
        launch = command or SERVERS[kind]
        self.processes = [
            subprocess.Popen(
                launch(config) + part, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True
            )
            for part in parts
        ]
        ready = [threading.Event() for _ in self.processes]

        def read(process: Any, ready: threading.Event) -> None:
            for line in process.stdout:  # drained to the end: a full pipe would stall the server
                if line.startswith("serving "):
                    ready.set()

        for process, event in zip(self.processes, ready, strict=True):
            threading.Thread(target=read, args=(process, event), daemon=True).start()
        for event in ready:
            if not event.wait(max(start_timeout - (time.monotonic() - began), 0.0)):
                self.stop()
                raise SystemExit(f"{kind}: not ready within {start_timeout:g} s")
        self.started = time.monotonic() - began

    def cpu(self) -> float:
        return sum(_cpu_seconds(process.pid) for process in self.processes)

    def stop(self, bound: float = 60) -> None:
        for process in self.processes:
            process.terminate()
        for process in self.processes:
            try:
                process.wait(timeout=bound)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait(timeout=30)


def idle(counts: list[int], window: float, settle: float) -> list[str]:
    rows = []
    for count in counts:
        robots = [f"r{index:04d}" for index in range(count)]
        shares = {}
        for kind in SERVERS:
            server = Server(kind, robots, 1.0)
            time.sleep(settle)
            before = server.cpu()
            time.sleep(window)
            shares[kind] = 100 * (server.cpu() - before) / window
            server.stop()
        rows.append(f"| {count} | {shares['dynevent']:.2f}% | {shares['peer']:.2f}% |")
        print(rows[-1], flush=True)
    return [
        "## ROS 2: an idle fleet in one process (bench/ros_fleet.py --idle)",
        "",
        f"CPU of the server process over {window:g} s, {settle:g} s after it is ready,",
        "as a share of one core.",
        "",
        *recorded.machine_description(("dynevent", "rclpy")),
        "",
        "| robots | dynevent serve | bare rclpy peer |",
        "|---|---|---|",
        *rows,
    ]


def start(counts: list[int]) -> list[str]:
    rows = []
    for count in counts:
        robots = [f"r{index:04d}" for index in range(count)]
        cells = []
        for kind, command in STARTS.items():
            server = Server(kind, robots, 1.0, command=command)
            cells.append(f"{server.started:.1f} s")
            server.stop(bound=5)  # then killed: only the start is measured
        rows.append(f"| {count} | " + " | ".join(cells) + " |")
        print(rows[-1], flush=True)
    return [
        "## ROS 2: a fleet's start (bench/ros_fleet.py --start)",
        "",
        "From the launch of the server process until it serves every robot (prints `serving`).",
        "",
        *recorded.machine_description(("dynevent", "rclpy")),
        "",
        "| robots | " + " | ".join(STARTS) + " |",
        "|---" * (len(STARTS) + 1) + "|",
        *rows,
    ]


def load(
    kind: str, robots: list[str], seconds: float, duration: float, shards: int = 1, drive: int | None = None
) -> tuple[list[str], bool]:
    import rclpy
    from rclpy.action import ActionClient
    from rclpy.executors import MultiThreadedExecutor
    from rmf_task_msgs.action import DynamicEvent

    server = Server(kind, robots, duration, shards)
    context = rclpy.Context()
    rclpy.init(context=context)
    node = rclpy.create_node("bench_fleet_load", context=context)
    # the clients before the node spins: an ActionClient made while its node spins can kill the
    # executor's thread (rclpy adds it to the node before its lock exists; docs/ros.md), and then
    # no goal of this process is ever answered
    clients = {
        robot: ActionClient(node, DynamicEvent, f"rmf/dynamic_event/command/benchFleet/{robot}")
        for robot in robots[:drive]
    }
    executor = MultiThreadedExecutor(num_threads=2, context=context)
    executor.add_node(node)
    threading.Thread(target=executor.spin, daemon=True).start()
    for robot, client in clients.items():
        if not client.wait_for_server(timeout_sec=60):
            raise SystemExit(f"no server for {robot}")
    # a server is "ready" for a client once the client's endpoints match the server's; the server's
    # replies match the client a moment later, and a reply sent before that is dropped by the DDS
    # layer (the goal then waits forever): let discovery settle
    time.sleep(2.0)
    lock = threading.Lock()
    trips: list[float] = []
    results: dict[tuple[str, int], int] = {}
    problems: list[str] = []
    stop_at = time.monotonic() + seconds

    def drive(robot: str, client: Any) -> None:
        count = 0
        while time.monotonic() < stop_at:
            second = time.monotonic() + 1.0
            count += 1
            key = (robot, count)
            done = threading.Event()
            started = time.perf_counter()

            def on_result(future: Any, key: tuple[str, int] = key, done: threading.Event = done) -> None:
                with lock:
                    results[key] = results.get(key, 0) + 1
                    if future.result().result.status != "completed":
                        problems.append(f"{key}: ended {future.result().result.status!r}")
                done.set()

            def on_response(future: Any, key: tuple[str, int] = key, done: threading.Event = done) -> None:
                handle = future.result()
                if not handle.accepted:
                    with lock:
                        problems.append(f"{key}: refused")
                    done.set()
                    return
                handle.get_result_async().add_done_callback(on_result)

            goal = DynamicEvent.Goal(
                dynamic_event_seq=1, event_type=1, category="go_to_place", description='"a"', id=0
            )
            client.send_goal_async(goal).add_done_callback(on_response)
            if not done.wait(30):
                with lock:
                    problems.append(f"{key}: no answer within 30 s (lost)")
                return
            with lock:
                trips.append(time.perf_counter() - started)
            time.sleep(max(second - time.monotonic(), 0.0))

    started = server.started
    cpu_before = server.cpu()
    wall = time.monotonic()
    threads = [threading.Thread(target=drive, args=item, daemon=True) for item in clients.items()]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(timeout=seconds + 60)
    wall = time.monotonic() - wall
    cpu = server.cpu() - cpu_before
    server.stop()
    executor.shutdown(timeout_sec=2)
    for client in clients.values():
        client.destroy()
    node.destroy_node()
    rclpy.try_shutdown(context=context)
    twice = [key for key, count in results.items() if count > 1]
    overheads = sorted(trip - duration for trip in trips) or [float("nan")]
    rate = len(trips) / wall
    p50, p99 = statistics.median(overheads), overheads[int(0.99 * (len(overheads) - 1))]
    name = kind if shards == 1 else f"{kind}, {shards} processes"
    name += f" ({len(robots)} robots, {started:.0f} s to start)"
    row = (
        f"| {name} | {rate:.1f} | {100 * cpu / wall:.0f}% | {rate / max(cpu / wall, 1e-9):.0f} | "
        f"{p50 * 1e3:.1f} ms | {p99 * 1e3:.1f} ms | {len(twice)} | {len(problems)} |"
    )
    print(row, flush=True)
    for problem in problems[:10]:
        print(f"  - {problem}", flush=True)
    return [row], not (twice or problems)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", type=int, default=100)
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--duration", type=float, default=0.2, help="a child's simulated duration (s)")
    parser.add_argument("--idle", metavar="N,N,...", help="measure idle CPU for these fleet sizes")
    parser.add_argument("--window", type=float, default=20.0, help="idle: seconds of CPU measured")
    parser.add_argument("--settle", type=float, default=5.0, help="idle: seconds waited after ready")
    parser.add_argument(
        "--shards",
        metavar="N,N,...",
        help="load: dynevent serve split over each of these numbers of processes (--shard), no peer",
    )
    parser.add_argument("--drive", type=int, help="load: drive only this many of the robots")
    parser.add_argument("--start", metavar="N,N,...", help="measure the start of these fleet sizes")
    parser.add_argument("--write", action="store_true", help="record the result in bench/results.md")
    args = parser.parse_args(argv)
    os.environ.setdefault("ROS_DOMAIN_ID", str(random.randint(150, 200)))
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    if args.start:
        lines = start([int(count) for count in args.start.split(",")])
        print("\n".join(lines))
        if args.write:
            recorded.write_section("ros-fleet-start", lines)
        return 0
    if args.idle:
        lines = idle([int(count) for count in args.idle.split(",")], args.window, args.settle)
        print("\n".join(lines))
        if args.write:
            recorded.write_section("ros-fleet-idle", lines)
        return 0
    robots = [f"r{index:04d}" for index in range(args.robots)]
    header = [
        "## ROS 2: a simulated fleet in one process under load (bench/ros_fleet.py)",
        "",
        f"{args.robots} robots, {args.drive or args.robots} of them each sent one NEXT a second for "
        f"{args.seconds:g} s by a plain rclpy client;",
        f"a child takes {args.duration:g} s with one progress report.  Overhead: the round trip (send to",
        "result) minus the child's own time.",
        "",
        *recorded.machine_description(("dynevent", "rclpy")),
        "",
        "| server | goals/s | server CPU | goals/s per core | overhead p50 | overhead p99 | answered twice "
        "| lost, refused or failed |",
        "|---|---|---|---|---|---|---|---|",
    ]
    print("\n".join(header), flush=True)
    rows, clean = [], True
    runs = [("dynevent", int(count)) for count in args.shards.split(",")] if args.shards else []
    for kind, shards in runs or [(kind, 1) for kind in SERVERS]:
        row, ok = load(kind, robots, args.seconds, args.duration, shards, args.drive)
        rows.extend(row)
        clean = clean and ok
    if args.write and clean:
        recorded.write_section("ros-fleet-shards" if runs else "ros-fleet", header + rows)
        print(f"wrote {recorded.RESULTS}", file=sys.stderr)
    return 0 if clean else 1


if __name__ == "__main__":
    sys.exit(main())
