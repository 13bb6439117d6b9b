"""Faults together, across hosts: the server's host killed (kill -9) while cut off and restarted on
its store (R21.4 across hosts), and two clients on two hosts racing for one robot (R5.2, R19.1), with
serve's client judge and `check` on a third host's recording agreeing."""

from __future__ import annotations

import re
import sys
import time
from collections.abc import Callable

import pytest
from sites import START, RosSite

from dynevent.tools.live import OFFLINE
from dynevent.wire.names import action_name, status_topic

#: DDS's lease (Fast DDS's default).
LEASE = 20.0


@pytest.mark.spec("R21.1", "R21.4", "R21.5")
def test_a_server_killed_while_cut_off_answers_after_its_restart(ros_site: Callable[..., RosSite]) -> None:
    site = ros_site(["server", "client"])
    categories = {"go_to_place": {"duration": 0.5, "report_every": 0.25}, "long": {"duration": 600}}
    store = str(site.folder / "fleet.db")
    serve = site.serve("server", ["r1"], categories, "--state", store)
    send = site.dynevent("client", "send", "--robot", "r1", "--category", "long", "--description", "{}",
                         "--timeout", str(LEASE * 3 + START * 2))  # fmt: skip
    send.wait_line("[id 2] underway", START)
    site["server"].block()  # its link up: a process started with its link down is never found (below)
    serve.kill()  # kill -9 while nobody can hear of it
    restarted = site.serve("server", ["r1"], categories, "--state", store)
    assert not restarted.saw(OFFLINE), restarted.output
    time.sleep(LEASE + 5)  # the client loses contact with the dead process
    site["server"].unblock()
    assert send.finish(START * 2) == 1, send.output  # aborted: nothing a restart can carry on
    assert send.saw("lost contact with tinyRobot/r1"), send.output
    assert send.saw("back in contact with tinyRobot/r1"), send.output
    assert send.saw("outcome: execution_failure: could not begin: server restarted"), send.output
    assert restarted.saw("answer: goal"), restarted.output  # the restart answered the goal it held
    after = site.dynevent("client", "send", "--robot", "r1", "--place", "pantry", "--timeout", str(START))
    assert after.finish(START * 2) == 0, after.output  # the robot was not blocked by the dead process
    assert "outcome: completed" in after.output


@pytest.mark.spec("R5.2", "R19.1", "R22.4")
def test_two_clients_on_two_hosts_racing_for_one_robot(ros_site: Callable[..., RosSite]) -> None:
    site = ros_site(["server", "left", "right", "recorder"])
    categories = {"go_to_place": {"duration": 1.0, "report_every": 0.5}}
    serve = site.serve("server", ["raced"], categories, "--rebegin", "0.5")
    bag = site.folder / "bag"
    record = site.dynevent("recorder", "record", "--output", str(bag))
    for topic in (
        status_topic("tinyRobot", "raced"),
        action_name("tinyRobot", "raced") + "/_action/feedback",
    ):
        record.wait_line(f"hearing /{topic}", START)
    rounds = 4
    outcomes: list[tuple[int, int]] = []
    for _ in range(rounds):
        send = ("send", "--robot", "raced", "--place", "pantry", "--timeout", str(START))
        racers = [site.dynevent(host, *send) for host in ("left", "right")]
        codes = [racer.finish(START * 2) for racer in racers]
        for racer in racers:  # each goal has one outcome: won, or lost the race (refused, or aborted)
            assert len(re.findall(r"^(outcome|not sent):", racer.output, re.MULTILINE)) == 1, racer.output
        outcomes.append((codes.count(0), codes.count(1)))
        if codes.count(0) == 2:
            continue  # one after the other: no race this round
        loser = racers[codes.index(1)]
        assert re.search(r"outcome: (rejected|execution_failure)|not sent: ", loser.output), loser.output
    assert all(won >= 1 for won, _ in outcomes), outcomes  # the robot always ran one of them
    assert record.stop() == 0, record.output
    check = site.site["recorder"].run([sys.executable, "-m", "dynevent", "check", str(bag)], START)
    assert check.returncode == 0, check.output
    serve.stop()
    judged = serve.wait_line("client judgement", 1)
    # a client that lost a race sent its NEXT while the robot waited: no rule of section 22 is broken,
    # the runs the clients left open aside (send ends no run)
    findings = re.findall(r"(R22\.\d+) \w+ x\d+", judged)
    assert set(findings) <= {"R22.8"}, serve.output


def test_a_server_started_while_its_link_is_down_says_it_will_not_be_found(
    ros_site: Callable[..., RosSite],
) -> None:
    """Fast DDS takes the interfaces that are up when a process starts: a server started before its
    host's network came up is never found from another host, and says so as it starts."""
    site = ros_site(["server", "client"])
    with site["server"].partition():
        serve = site.serve("server", ["r1"], {"go_to_place": {"duration": 0.5}})
    assert serve.saw(OFFLINE), serve.output
    again = site.serve("server", ["r2"], {"go_to_place": {"duration": 0.5}})  # the network is up now
    assert not again.saw(OFFLINE), again.output
