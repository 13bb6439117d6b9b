"""No answer lost to a partition (R21.5): a client and its robot's server on two hosts, the network
between them cut for 5 s, 30 s and 120 s, and `dynevent send` still ends with the answer the server
gave, whether the child ended during the partition or after it.

Every partition runs at once, each on a site of its own: on three the client's host is cut, on
three the server's.  On each, one `send` drives a child that ends while the network is cut and
another one a child that ends after it heals.  On the sites whose client is cut, a third host
drives the robot whose child ended during the partition once it has: the cut-off client's goal
blocks nothing (R21.5).
"""

from __future__ import annotations

import concurrent.futures
import threading
import time
from collections.abc import Callable

import pytest
from hosts import HostProcess
from sites import START, RosSite

#: DDS's lease (Fast DDS's default): a partition shorter than this loses nothing and is no lost contact.
LEASE = 20.0
#: Seconds from both children's start to the cut.
BEFORE_CUT = 2.0
#: Seconds from the heal to the end of the child that ends after the partition.
AFTER_HEAL = 8.0
#: The bound on what follows the heal: DDS finds the lost participant again (its announcements come
#: every few seconds), the client asks again, and the answer comes.
AFTER = 45.0


def _sends(site: RosSite, host: str, cut: float) -> tuple[HostProcess, HostProcess]:
    """Two sends from ``host``: to r1, a child that ends halfway through the partition, and to r2,
    one that ends after it; both once their children run."""
    bound = str(BEFORE_CUT + cut + AFTER_HEAL + AFTER + START)
    during = site.dynevent(host, "send", "--robot", "r1", "--category", "during", "--description", "{}",
                           "--timeout", bound)  # fmt: skip
    after = site.dynevent(host, "send", "--robot", "r2", "--category", "after", "--description", "{}",
                          "--timeout", bound)  # fmt: skip
    for send in (during, after):
        send.wait_line("underway", START)
    return during, after


def _site(ros_site: Callable[..., RosSite], cut: float, names: list[str]) -> tuple[RosSite, HostProcess]:
    site = ros_site(names)
    categories = {
        "during": {"duration": BEFORE_CUT + cut / 2, "report_every": 1.0},
        "after": {"duration": BEFORE_CUT + cut + AFTER_HEAL, "report_every": 1.0},
        "go_to_place": {"duration": 1.0, "report_every": 0.5},
    }
    return site, site.serve("server", ["r1", "r2"], categories)


def _scenario(ros_site: Callable[..., RosSite], cut: float, side: str) -> None:
    """One site, ``side``'s host cut for ``cut`` seconds once both children run: both sends end with
    their answers.  Where the client is cut, another client drives r1 once its child has ended."""
    site, serve = _site(ros_site, cut, ["server", "client", "other"])
    during, after = _sends(site, "client", cut)
    time.sleep(BEFORE_CUT)
    site[side].cut()
    heal = threading.Timer(cut, site[side].heal)
    heal.start()
    try:
        if side == "client":  # the cut-off client's child ends; another client drives that robot at once
            serve.wait_line("tinyRobot/r1  answer: goal", BEFORE_CUT + cut + START)
            other = site.dynevent(
                "other", "send", "--robot", "r1", "--place", "pantry", "--timeout", str(START)
            )
            assert other.finish(START * 2) == 0, other.output
            assert "outcome: completed" in other.output
            if cut > LEASE:
                assert during.returncode is None, f"the cut-off send ended before the heal:\n{during.output}"
    finally:
        heal.join(cut + START)
    for send in (during, after):
        code = send.finish(AFTER_HEAL + AFTER + START)
        assert code == 0, f"the {side}'s host cut {cut:g} s:\n{send.output}"
        assert "outcome: completed: the event ended 'completed'" in send.output
        lost = send.saw("lost contact with tinyRobot/")
        back = send.saw("back in contact with tinyRobot/")
        # a partition past the lease is contact lost, and said; a shorter one loses nothing
        assert (lost, back) == ((True, True) if cut > LEASE else (False, False)), send.output
    assert serve.returncode is None, serve.output  # the server went on throughout


#: The partitions: each length, on each side, all at once (each on a site of its own).
PARTITIONS = [(cut, side) for cut in (5.0, 30.0, 120.0) for side in ("client", "server")]


@pytest.mark.spec("R21.4", "R21.5")
def test_a_partition_loses_no_answer_whichever_side_is_cut(ros_site: Callable[..., RosSite]) -> None:
    with concurrent.futures.ThreadPoolExecutor(len(PARTITIONS)) as pool:
        runs = {(cut, side): pool.submit(_scenario, ros_site, cut, side) for cut, side in PARTITIONS}
    failed = {f"the {side}'s host cut {cut:g} s": run.exception() for (cut, side), run in runs.items()}
    failed = {what: error for what, error in failed.items() if error is not None}
    assert not failed, "\n\n".join(f"{what}: {error}" for what, error in failed.items())
