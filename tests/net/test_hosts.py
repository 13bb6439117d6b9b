"""The test bed itself: hosts that reach each other and nothing else, and the faults put on them."""

from __future__ import annotations

import ipaddress
import json
import sys
import textwrap
from collections.abc import Callable, Sequence

from hosts import SUBNET, Site

#: A UDP receiver: counts the datagrams that come to port 9000 until one says "end" (or 5 s pass
#: with none), then prints the count, the bytes and the seconds from the first to the last.
RECEIVER = textwrap.dedent(
    """
    import socket, sys, time
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    s.bind(("0.0.0.0", 9000))
    s.settimeout(5.0)
    print("ready", flush=True)
    count = size = 0
    first = last = 0.0
    try:
        while True:
            data = s.recv(65536)
            if data == b"end":
                break
            last = time.monotonic()
            first = first or last
            count += 1
            size += len(data)
    except socket.timeout:
        pass
    print("received", count, size, last - first, flush=True)
    """
)

#: A UDP sender: ``count`` datagrams of ``size`` bytes to ``address``:9000, then "end" ten times (some
#: may be dropped).  A datagram the host's own firewall drops fails to send (EPERM) and counts as sent;
#: a network that cannot be reached ends it.
SENDER = textwrap.dedent(
    """
    import socket, sys, time
    address, count, size = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    s = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    sent = 0
    for _ in range(count):
        try:
            s.sendto(b"x" * size, (address, 9000))
        except PermissionError:
            pass
        except OSError as error:
            print("error", error.errno, flush=True)
            break
        sent += 1
        time.sleep(0.0005)
    time.sleep(0.2)
    for _ in range(10):
        try:
            s.sendto(b"end", (address, 9000))
        except OSError:
            pass
        time.sleep(0.01)
    print("sent", sent, flush=True)
    """
)


def _exchange(site: Site, count: int, size: int = 100) -> tuple[int, int, float]:
    """``count`` datagrams from host a to host b: how many arrived, their bytes, and the seconds from
    the first to the last."""
    receiver = site["b"].start([sys.executable, "-c", RECEIVER])
    receiver.wait_line("ready", 30)
    sender = site["a"].run([sys.executable, "-c", SENDER, site["b"].address, str(count), str(size)], 120)
    assert sender.returncode == 0, sender.output
    assert receiver.finish(30) == 0, receiver.output
    _, arrived, size_in, span = receiver.wait_line("received", 1).split()
    return int(arrived), int(size_in), float(span)


def test_hosts_reach_each_other_and_nothing_else(site: Callable[[Sequence[str]], Site]) -> None:
    bed = site(["a", "b"])
    for host in bed.hosts.values():
        assert ipaddress.ip_address(host.address) in ipaddress.ip_network("198.18.0.0/15")
        assert ipaddress.ip_address(host.address) in SUBNET
        routes = json.loads(host.run(["ip", "-j", "route"], 15).output)
        assert {route["dst"] for route in routes} == {str(SUBNET), "224.0.0.0/4"}  # no default route
    arrived, _, _ = _exchange(bed, 200)
    assert arrived == 200
    # any address off the site is unreachable at once: no route out of the machine
    sender = bed["a"].run([sys.executable, "-c", SENDER, "192.0.2.1", "1", "10"], 30)
    assert "error 101" in sender.output, sender.output  # ENETUNREACH


def test_a_partition_cuts_a_host_off_until_it_heals(site: Callable[[Sequence[str]], Site]) -> None:
    bed = site(["a", "b"])
    bed["a"].cut()
    arrived, _, _ = _exchange(bed, 100)
    assert arrived == 0
    bed["a"].heal()
    arrived, _, _ = _exchange(bed, 100)
    assert arrived == 100


def test_a_lossy_host_drops_its_share_each_way(site: Callable[[Sequence[str]], Site]) -> None:
    bed = site(["a", "b"])
    bed["a"].loss(30)  # what a sends loses 30%
    arrived, _, _ = _exchange(bed, 2000)
    assert 1200 <= arrived <= 1600, arrived  # 1400 expected; 4.9 standard deviations either side
    bed["a"].loss(0)
    bed["b"].loss(30)  # now what b receives loses 30%
    arrived, _, _ = _exchange(bed, 2000)
    assert 1200 <= arrived <= 1600, arrived
    bed["b"].loss(0)
    arrived, _, _ = _exchange(bed, 500)
    assert arrived == 500


def test_a_host_held_to_a_rate_sends_no_faster(site: Callable[[Sequence[str]], Site]) -> None:
    bed = site(["a", "b"])
    bed["a"].rate(800)  # 100 kB/s
    arrived, size, span = _exchange(bed, 1000, 1000)  # 1 MB offered, as fast as the sender can
    allowed = 100_000 * span + 16_000 + 1100  # the rate over the span, the bucket's burst, one more
    assert size <= allowed, (size, span)
    assert arrived < 1000  # the rest was dropped at the bucket
    bed["a"].rate(None)
    arrived, _, _ = _exchange(bed, 300, 1000)
    assert arrived == 300
