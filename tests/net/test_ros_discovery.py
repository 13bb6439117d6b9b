"""A fleet across hosts, in each of the three ways a site's processes find each other (sites.MODES):
serve's two shards on two hosts, and on two others `send`, an AsyncRobotClient, a behaviour tree,
`probe` and `record`, then `check` on the recording.  A robot that is not there is named within a
bound of its own, the discovery server's partial view included."""

from __future__ import annotations

import concurrent.futures
import sys
import time
from collections.abc import Callable
from pathlib import Path

import pytest
from sites import MODES, START, RosSite

from dynevent.tools.live.send import LOOK, SETTLED
from dynevent.wire.names import action_name, status_topic

ROBOTS = [f"r{n}" for n in range(1, 9)]
CLIENTS = str(Path(__file__).resolve().parent / "clients.py")
#: How long, once the graph shows the fleet, `send` takes at most to name a robot that is not there:
#: it looks for LOOK seconds and waits for the graph to stay the same for SETTLED (send's own
#: constants), plus what discovery takes to show the fleet and a process to start.
NAMED_WITHIN = LOOK + SETTLED + 20.0


def _shards(site: RosSite) -> list[list[str]]:
    """serve's two shards on hosts shard1 and shard2: the robots each serves."""
    categories = {"go_to_place": {"duration": 0.5, "report_every": 0.1}}
    served = []
    for index in (1, 2):
        serve = site.serve(f"shard{index}", ROBOTS, categories, "--shard", f"{index}/2", "--rebegin", "0.5",
                           "--first-seq", "4294967295")  # fmt: skip
        served.append(serve.wait_line("serving ", 1).rsplit(": ", 1)[1].split(", "))
    assert sorted(served[0] + served[1]) == sorted(ROBOTS), served
    return served


@pytest.mark.spec("R20.1", "R21.5")
def test_a_sharded_fleet_is_found_and_driven_from_other_hosts(ros_site: Callable[..., RosSite]) -> None:
    """Each way of finding the processes on a site of its own, all at once."""
    with concurrent.futures.ThreadPoolExecutor(len(MODES)) as pool:
        runs = {mode: pool.submit(_in_mode, ros_site, mode) for mode in MODES}
    failed = {mode: run.exception() for mode, run in runs.items() if run.exception() is not None}
    assert not failed, "\n\n".join(f"{mode}: {error}" for mode, error in failed.items())


def _in_mode(ros_site: Callable[..., RosSite], mode: str) -> None:
    site = ros_site(["shard1", "shard2", "client", "prober"], mode)
    first, second = _shards(site)
    bag = site.folder / "bag"
    record = site.dynevent("prober", "record", "--output", str(bag))
    heard = time.monotonic() + START  # what a topic carried before the recorder heard it is lost
    for robot in ROBOTS:
        for topic in (
            status_topic("tinyRobot", robot),
            action_name("tinyRobot", robot) + "/_action/feedback",
        ):
            record.wait_line(f"hearing /{topic}", max(heard - time.monotonic(), 0.0))
    # a robot of each shard, driven by send; two more by the asyncio client and a behaviour tree
    sends = [site.dynevent("client", "send", "--robot", robot, "--place", "pantry", "--timeout", str(START))
             for robot in (first[0], second[0])]  # fmt: skip
    drivers = [
        site.python("client", CLIENTS, "async", first[1]),
        site.python("client", CLIENTS, "bt", second[1]),
    ]
    probe = site.dynevent(
        "prober", "probe", "--robot", first[2], "--place", "pantry", "lounge", "--server-wait", str(START)
    )
    for process in (*sends, *drivers):
        assert process.finish(START * 2) == 0, process.output
    for send in sends:
        assert "outcome: completed" in send.output, send.output
    assert probe.finish(START * 4) == 0, probe.output
    # a robot that is not there, named by send once the graph has settled, within a bound of its own
    started = time.monotonic()
    missing = site.dynevent("client", "send", "--robot", "nobody", "--place", "pantry", "--timeout", "300")
    assert missing.finish(NAMED_WITHIN + START) == 2, missing.output
    took = time.monotonic() - started
    assert "no Dynamic Event server for tinyRobot/nobody once the graph settled" in missing.output
    assert f"the graph has fleet tinyRobot: {len(ROBOTS)} robot(s)" in missing.output, missing.output
    assert took < NAMED_WITHIN + START, took
    assert record.stop() == 0, record.output
    check = site.site["prober"].run([sys.executable, "-m", "dynevent", "check", str(bag)], START)
    assert check.returncode == 0, check.output
