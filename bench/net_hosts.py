"""A fleet across hosts (tests/net's test bed: network namespaces on one bridge), measured.

- ``roundtrip``: a NEXT's round trip (send to answer, through dynevent's client and ``dynevent serve``
  with children that end at once) from a client on another host, beside the same from a client on
  the server's own host, in alternating batches of one run so that both share the machine's noise;
  reported as medians, p90s and the ratio of the two.
- ``discovery``: a fleet of ``--robots`` robots split over two hosts (``serve --shard 1/2`` and
  ``2/2``), in each way a site finds its processes (multicast, static peers, a discovery server):
  how long a client started on a third host takes to find the last robot of each shard (its server
  and status, ``RobotClient.ready``) and to see the whole fleet on the graph, and the discovery
  traffic the site's links carried from the servers' start until then (bytes and packets, from
  the kernel's counters of each host's link).

Needs root, ``ip`` and ``nft`` (tests/net) and ROS 2 with ``rmf_task_msgs`` (``. build/ros/env.sh``).

    python bench/net_hosts.py [--quick] [--write] [--robots N] [--goals N]

``--write`` records the results as the ``net-hosts`` section of bench/results.md.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
for folder in (ROOT, ROOT / "tests" / "net", ROOT / "tests" / "ros"):
    if str(folder) not in sys.path:  # run as a script: the bench and the test bed importable
        sys.path.insert(0, str(folder))

from hosts import Site, missing  # noqa: E402
from sites import MODES, START, RosSite  # noqa: E402

from bench import results  # noqa: E402
from dynevent.sim.config import shard_of  # noqa: E402

#: A client of one robot: ``ready``, then batches of NEXTs on its command (a line ``go N`` on its
#: standard input), each batch's round trips printed as one JSON line.
ROUND_TRIP_CLIENT = r"""
import json, sys, time
from dynevent.ros import RobotClient
with RobotClient("tinyRobot", sys.argv[1], node_name="bench_" + sys.argv[1]) as robot:
    robot.ready(60)
    print("ready", flush=True)
    for line in sys.stdin:
        took = []
        for _ in range(int(line.split()[1])):
            started = time.perf_counter()
            outcome = robot.next("go_to_place", '"pantry"').wait(30)
            took.append(time.perf_counter() - started)
            assert outcome.kind.value == "completed", outcome
        print(json.dumps(took), flush=True)
"""

#: A client started on a host of its own: when it found each robot named, and the whole fleet.
DISCOVERY_CLIENT = r"""
import json, sys, time
started = time.monotonic()
from dynevent.ros import RobotClient
from dynevent.ros.graph import servers_seen
found = {}
clients = [RobotClient("tinyRobot", robot, node_name="finder_" + robot).open() for robot in sys.argv[2:]]
imported = time.monotonic() - started
for client, robot in zip(clients, sys.argv[2:]):
    client.ready(300)
    found[robot] = time.monotonic() - started
node = clients[0]._session.node
while len(servers_seen(node)) < int(sys.argv[1]):
    time.sleep(0.05)
    assert time.monotonic() - started < 300, len(servers_seen(node))
whole = time.monotonic() - started
for client in clients:
    client.close()
print(json.dumps({"imported": imported, "found": found, "whole": whole}), flush=True)
"""


def _percentile(values: list[float], share: float) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(share * len(ordered)))]


def round_trip(goals: int, batch: int) -> list[str]:
    """The round trip from another host beside the one from the server's host."""
    with tempfile.TemporaryDirectory() as folder:
        site = RosSite(Site(["server", "far"]), "multicast", Path(folder))
        try:
            categories = {"go_to_place": {"duration": 0.001, "report_every": 1.0}}
            site.serve("server", ["near", "far"], categories)
            clients = {
                "same host": site.python("server", "-c", ROUND_TRIP_CLIENT, "near", stdin=True),
                "another host": site.python("far", "-c", ROUND_TRIP_CLIENT, "far", stdin=True),
            }
            for client in clients.values():
                client.wait_line("ready", START)
            took: dict[str, list[float]] = {name: [] for name in clients}
            for _ in range(max(goals // batch, 1)):
                for name, client in clients.items():
                    seen = len(client.lines)
                    client.write(f"go {batch}\n")
                    deadline = time.monotonic() + batch * 30
                    while len(client.lines) == seen:
                        assert time.monotonic() < deadline, client.output
                        time.sleep(0.01)
                    took[name].extend(json.loads(client.lines[-1]))
        finally:
            site.close()
    near, far = took["same host"], took["another host"]
    lines = [
        "| client | goals | median | p90 |",
        "|---|---|---|---|",
    ]
    for name, values in took.items():
        lines.append(
            f"| {name} | {len(values)} | {statistics.median(values) * 1000:.1f} ms | "
            f"{_percentile(values, 0.9) * 1000:.1f} ms |"
        )
    ratio = statistics.median(far) / statistics.median(near)
    lines += ["", f"Across hosts the median round trip is {ratio:.2f} times the one on the server's host."]
    return lines


def _traffic(site: Site) -> dict[str, int]:
    counted = {"bytes": 0, "packets": 0}
    for host in site.hosts.values():
        counters = host.counters()
        counted["bytes"] += counters["tx_bytes"]
        counted["packets"] += counters["tx_packets"]
    return counted


def discovery(robots: int) -> list[str]:
    """A fleet of ``robots`` over two hosts, found from a third, in each mode."""
    names = [f"r{n:04d}" for n in range(robots)]
    lines = [
        "| discovery | serving (both shards) | last robot of each shard found | whole fleet on the graph "
        "| traffic until then (all links, sent) |",
        "|---|---|---|---|---|",
    ]
    for mode in MODES:
        with tempfile.TemporaryDirectory() as folder:
            site = RosSite(Site(["shard1", "shard2", "client"]), mode, Path(folder))
            try:
                before = _traffic(site.site)
                started = time.monotonic()
                categories = {"go_to_place": {"duration": 0.001}}
                config = site.file("fleet.json", {"robots": names, "rebegin": 0, "categories": categories})
                serves = [site.dynevent(f"shard{index}", "serve", "--config", str(config), "--shard",
                                        f"{index}/2") for index in (1, 2)]  # fmt: skip
                for serve in serves:
                    serve.wait_line("serving ", 600)
                serving = time.monotonic() - started
                last = [[name for name in names if shard_of(name, 2) == index][-1] for index in (1, 2)]
                # through a discovery server a client sees only what it matches: the graph whole needs a
                # super client, as send, probe and record make theirs
                super_client = {"ROS_SUPER_CLIENT": "TRUE"} if mode == "discovery_server" else {}
                client = site.python("client", "-c", DISCOVERY_CLIENT, str(robots), *last, env=super_client)
                assert client.finish(900) == 0, client.output
                report: dict[str, Any] = json.loads(client.wait_line('{"imported"', 1))
                traffic = _traffic(site.site)
            finally:
                site.close()
        found = max(report["found"].values()) - report["imported"]
        whole = report["whole"] - report["imported"]
        sent = traffic["bytes"] - before["bytes"]
        packets = traffic["packets"] - before["packets"]
        print(f"net_hosts: {mode}: {found:.1f} s, {whole:.1f} s", file=sys.stderr, flush=True)
        lines.append(
            f"| {mode.replace('_', ' ')} | {serving:.1f} s | {found:.1f} s | {whole:.1f} s | "
            f"{sent / 1e6:.1f} MB in {packets:,} packets |"
        )
    return lines


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--goals", type=int, default=200, help="round trips from each client")
    parser.add_argument("--robots", type=int, default=1000, help="the fleet found across hosts")
    parser.add_argument("--quick", action="store_true", help="40 goals, 100 robots")
    parser.add_argument("--write", action="store_true", help="record the results in bench/results.md")
    args = parser.parse_args()
    why = missing()
    if why is not None:
        print(f"net_hosts: {why}", file=sys.stderr)
        return 2
    goals, robots = (40, 100) if args.quick else (args.goals, args.robots)
    lines = [
        "## A fleet across hosts (bench/net_hosts.py)",
        "",
        "Hosts are network namespaces on one bridge (tests/net), so the network adds no delay: what "
        "crossing hosts costs here is the middleware's own.",
        "",
        *results.machine_description(["dynevent", "rclpy"]),
        "",
        f"A NEXT's round trip through dynevent's client and `dynevent serve`, {goals} goals from each "
        "client, in alternating batches of 20:",
        "",
        *round_trip(goals, 20),
        "",
        f"A fleet of {robots} robots over two hosts, found by a client started on a third (times from "
        "the client's rclpy import; traffic from the servers' start):",
        "",
        *discovery(robots),
    ]
    print("\n".join(lines))
    if args.write:
        results.write_section("net-hosts", lines)
    return 0


if __name__ == "__main__":
    sys.exit(main())
