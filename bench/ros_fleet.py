"""A fleet of simulated robots in one ``dynevent serve`` process, each taking one NEXT per second.

``dynevent serve`` runs ``--robots`` robots whose ``go_to_place`` takes
``--duration`` seconds with one progress report; a load process (one node,
a plain rclpy action client per robot) sends each robot a NEXT (id 0, the
server numbers it) once a second, the next one as soon as the previous
answered and its second is over.  After ``--seconds`` it checks that every
goal sent got exactly one result and that no goal failed, and reports the
round trips (send to result, the child's simulated duration included) at the
median and p99, goals per second, and the serve process's CPU time.

    python bench/ros_fleet.py [--robots 100] [--seconds 60] [--duration 0.2] [--write]

``--write`` records the result as the ``ros-fleet`` section of bench/results.md.
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


def _cpu_seconds(pid: int) -> float:
    fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / TICKS  # utime + stime


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--robots", type=int, default=100)
    parser.add_argument("--seconds", type=float, default=60.0)
    parser.add_argument("--duration", type=float, default=0.2, help="a child's simulated duration (s)")
    parser.add_argument("--write", action="store_true", help="record the result in bench/results.md")
    args = parser.parse_args(argv)
    os.environ.setdefault("ROS_DOMAIN_ID", str(random.randint(150, 200)))
    os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
    robots = [f"r{index:03d}" for index in range(args.robots)]
    folder = Path(tempfile.mkdtemp(prefix="dynevent-fleet-"))
    config = folder / "fleet.json"
    spec = {"duration": args.duration, "report_every": args.duration / 2}
    config.write_text(
        json.dumps(
            {"fleet": "benchFleet", "robots": robots, "rebegin": 0, "categories": {"go_to_place": spec}}
        )
    )
    serve = subprocess.Popen(
        [sys.executable, "-m", "dynevent", "serve", "--config", str(config)],
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )

    import rclpy
    from rclpy.action import ActionClient
    from rclpy.executors import MultiThreadedExecutor
    from rmf_task_msgs.action import DynamicEvent

    rclpy.init()
    node = rclpy.create_node("bench_fleet_load")
    executor = MultiThreadedExecutor(num_threads=2)
    executor.add_node(node)
    threading.Thread(target=executor.spin, daemon=True).start()
    clients = {
        robot: ActionClient(node, DynamicEvent, f"rmf/dynamic_event/command/benchFleet/{robot}")
        for robot in robots
    }
    for robot, client in clients.items():
        if not client.wait_for_server(timeout_sec=60):
            raise SystemExit(f"no server for {robot}")
    lock = threading.Lock()
    trips: list[float] = []
    results: dict[tuple[str, int], int] = {}
    problems: list[str] = []
    stop_at = time.monotonic() + args.seconds

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

    cpu_before = _cpu_seconds(serve.pid)
    wall = time.monotonic()
    threads = [threading.Thread(target=drive, args=item, daemon=True) for item in clients.items()]
    for thread in threads:
        thread.start()
    for thread in threads:
        thread.join(timeout=args.seconds + 60)
    wall = time.monotonic() - wall
    cpu = _cpu_seconds(serve.pid) - cpu_before
    serve.terminate()
    serve.wait(timeout=30)
    executor.shutdown(timeout_sec=2)
    rclpy.try_shutdown()
    twice = [key for key, count in results.items() if count > 1]
    ordered = sorted(trips) or [float("nan")]
    lines = [
        "## ROS 2: a simulated fleet in one `dynevent serve` (bench/ros_fleet.py)",
        "",
        f"{args.robots} robots, each sent one NEXT a second for {args.seconds:g} s by a plain rclpy client;",
        f"a child takes {args.duration:g} s (included in the round trip) with one progress report.",
        "",
        *recorded.machine_description(("dynevent", "rclpy")),
        "",
        f"- goals answered: {len(trips)} ({len(trips) / wall:.1f} per second)",
        f"- round trip, send to result: median {statistics.median(ordered) * 1e3:.1f} ms, "
        f"p99 {ordered[int(0.99 * (len(ordered) - 1))] * 1e3:.1f} ms",
        f"- serve's CPU: {cpu:.1f} s in {wall:.1f} s, {100 * cpu / wall:.0f}% of one core",
        f"- answered twice: {len(twice)}; lost, refused or failed: {len(problems)}",
        *(f"  - {problem}" for problem in problems[:10]),
    ]
    print("\n".join(lines))
    if args.write and not (twice or problems):
        recorded.write_section("ros-fleet", lines)
        print(f"wrote {recorded.RESULTS}", file=sys.stderr)
    return 1 if twice or problems else 0


if __name__ == "__main__":
    sys.exit(main())
