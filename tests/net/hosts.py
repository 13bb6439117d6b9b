"""A test bed of hosts on one machine: network namespaces joined by a bridge, with the network's faults.

A :class:`Site` is a bridge in a network namespace of its own and one namespace per host, each host
joined to the bridge by a veth pair, with an address of RFC 2544's benchmarking range
(198.18.0.0/15) and no route out of the machine: a process on a host reaches the other hosts of its
site and nothing else (not even another site's hosts, nor the machine's own loopback).  A test
makes its site, runs commands on its hosts (:meth:`Host.start`, :meth:`Host.run`: a
:class:`HostProcess`, its output read live, every wait bounded) and puts faults on them:

- :meth:`Host.cut` and :meth:`Host.heal`: a partition, the host's link down on the bridge's side
  (the host keeps its address and sees its link lose its carrier), then up; :meth:`Host.block` and
  :meth:`Host.unblock`: a partition past the link, which stays up (everything on it dropped);
- :meth:`Host.loss`: the host drops a share of what it sends and what it receives (nftables,
  ``numgen random``), on its site link only (its own loopback is spared);
- :meth:`Host.rate`: the host's sending bandwidth (a ``tbf`` qdisc).

This kernel has no ``netem`` qdisc (:func:`netem_missing` checks), so there is no delay, jitter,
duplication or reordering by tc: faults are losses, partitions and bandwidth.

It needs root, ``ip`` (iproute2) with network namespaces, and ``nft`` (Debian's ``nftables``):
:func:`missing` says what is not there, in one line.  Namespaces are named ``dvt<pid>s<n>-<host>``;
a site removes its own at :meth:`Site.close`, and a new one removes those of processes that are
gone (a test run killed by a signal cannot clean up after itself).
"""

from __future__ import annotations

import contextlib
import ipaddress
import itertools
import json
import os
import shutil
import signal
import subprocess
import threading
import time
from collections.abc import Iterator, Mapping, Sequence

#: The site's subnet: RFC 2544's benchmarking range, which no real network routes.  Every site has
#: the same one; sites never meet (each has a bridge of its own).
SUBNET = ipaddress.ip_network("198.18.0.0/24")
#: The first host's address in :data:`SUBNET`; the next hosts take the addresses after it.
FIRST_HOST = 11
#: The prefix of every namespace the test bed makes.
PREFIX = "dvt"
#: The bound on one ``ip`` or ``nft`` command, in seconds.
COMMAND_BOUND = 15.0
#: The bound on a host's process's close (a signal, then SIGKILL), in seconds.
CLOSE_BOUND = 20.0

_sites = itertools.count(1)  # the sites this process made, to name the next


class NetError(RuntimeError):
    """A command of the test bed failed: its words, exit status and output."""


def _ip(*words: str, check: bool = True) -> subprocess.CompletedProcess[str]:
    return _command(["ip", *words], check=check)


def _command(
    argv: Sequence[str], *, check: bool = True, stdin: str | None = None
) -> subprocess.CompletedProcess[str]:
    done = subprocess.run(
        list(argv), input=stdin, capture_output=True, text=True, timeout=COMMAND_BOUND, check=False
    )
    if check and done.returncode != 0:
        raise NetError(
            f"{' '.join(argv)}: exit {done.returncode}: {done.stderr.strip() or done.stdout.strip()}"
        )
    return done


def missing() -> str | None:
    """Why no site can be made here (one line), or None when one can: root, ``ip netns`` and ``nft``."""
    if os.geteuid() != 0:
        return "the hosts' test bed needs root (network namespaces)"
    for tool, package in (("ip", "iproute2"), ("nft", "nftables")):
        if shutil.which(tool) is None:
            return f"the hosts' test bed needs {tool!r} (Debian's {package})"
    probe = f"{PREFIX}{os.getpid()}probe"
    made = _ip("netns", "add", probe, check=False)
    if made.returncode != 0:
        return f"the hosts' test bed cannot make a network namespace: {made.stderr.strip()}"
    try:
        table = _command(["ip", "netns", "exec", probe, "nft", "add", "table", "inet", "probe"], check=False)
        if table.returncode != 0:
            return f"nftables does not work in a network namespace here: {table.stderr.strip()}"
    finally:
        _ip("netns", "delete", probe, check=False)
    return None


def netem_missing() -> bool:
    """This kernel has no ``netem`` qdisc (delay, reordering): the test bed's faults are losses,
    partitions and bandwidth."""
    probe = f"{PREFIX}{os.getpid()}netem"
    _ip("netns", "add", probe)
    try:
        added = _command(
            [
                "ip",
                "netns",
                "exec",
                probe,
                "tc",
                "qdisc",
                "add",
                "dev",
                "lo",
                "root",
                "netem",
                "delay",
                "1ms",
            ],
            check=False,
        )
        return added.returncode != 0
    finally:
        _ip("netns", "delete", probe, check=False)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def remove_abandoned() -> list[str]:
    """Remove the namespaces of test processes that are gone; the names removed."""
    listed = _ip("netns", "list", check=False).stdout.split("\n")
    removed = []
    for line in listed:
        name = line.split(" ", 1)[0]
        if not name.startswith(PREFIX):
            continue
        digits = name[len(PREFIX) :].split("s", 1)[0].split("probe", 1)[0].split("netem", 1)[0]
        if digits.isdigit() and not _alive(int(digits)):
            _ip("netns", "delete", name, check=False)
            removed.append(name)
    return removed


class Host:
    """One host of a :class:`Site`: a network namespace with one link, ``eth0``, to the site's bridge."""

    def __init__(self, site: Site, name: str, index: int) -> None:
        self.site = site
        self.name = name
        self.netns = f"{site.tag}-{name}"
        self.address = str(SUBNET.network_address + FIRST_HOST + index)
        self.port = f"p{index}"  # the link's end on the bridge
        self.processes: list[HostProcess] = []

    def __repr__(self) -> str:
        return f"Host({self.name!r}, {self.address})"

    # ------------------------------------------------------------- processes

    def _argv(self, argv: Sequence[str]) -> list[str]:
        return ["ip", "netns", "exec", self.netns, *argv]

    def start(
        self, argv: Sequence[str], env: Mapping[str, str] | None = None, *, stdin: bool = False
    ) -> HostProcess:
        """Start ``argv`` on this host, its output (standard error with it) read live, its input a pipe
        (:meth:`HostProcess.write`) when ``stdin``; the site ends it at its close if it still runs."""
        process = HostProcess(self, self._argv(argv), env, stdin=stdin)
        self.processes.append(process)
        return process

    def run(self, argv: Sequence[str], timeout: float, env: Mapping[str, str] | None = None) -> HostProcess:
        """Run ``argv`` on this host to its end, at most ``timeout`` seconds (then the test fails with
        its output)."""
        process = self.start(argv, env)
        process.finish(timeout)
        return process

    # ------------------------------------------------------------- faults

    def cut(self) -> None:
        """A partition: the host's link goes down on the bridge's side (the host sees its link lose its
        carrier, as when a cable is pulled or Wi-Fi drops)."""
        _ip("-n", self.site.bridge_netns, "link", "set", self.port, "down")

    def heal(self) -> None:
        """The partition ends: the link is up again."""
        _ip("-n", self.site.bridge_netns, "link", "set", self.port, "up")

    def _drop(self, table: str, incoming: str, outgoing: str) -> None:
        """An nftables table of the host's that drops what its rules match, received and sent."""
        rules = (
            f"table inet {table} {{\n"
            f"  chain incoming {{ type filter hook input priority 0; {incoming} drop; }}\n"
            f"  chain outgoing {{ type filter hook output priority 0; {outgoing} drop; }}\n"
            "}\n"
        )
        _command(["ip", "netns", "exec", self.netns, "nft", "-f", "-"], stdin=rules)

    def _undrop(self, table: str) -> None:
        _command(["ip", "netns", "exec", self.netns, "nft", "delete", "table", "inet", table], check=False)

    def block(self) -> None:
        """A partition past the host's link (a failed switch or router): the link stays up, and
        everything the host sends or receives on it is dropped."""
        self._drop("dvblock", 'iifname "eth0"', 'oifname "eth0"')

    def unblock(self) -> None:
        """The partition past the link ends."""
        self._undrop("dvblock")

    @contextlib.contextmanager
    def partition(self) -> Iterator[None]:
        """Cut while the block runs, healed after it, however it ends."""
        self.cut()
        try:
            yield
        finally:
            self.heal()

    def loss(self, percent: int) -> None:
        """The host drops ``percent`` % of the packets it sends and of those it receives on its link,
        each drawn at random (0 ends the loss)."""
        if not 0 <= percent <= 100:
            raise ValueError(f"loss: a percentage from 0 to 100 (got {percent})")
        self._undrop("dvloss")
        if percent:
            share = f"numgen random mod 100 < {percent}"
            self._drop("dvloss", f'iifname "eth0" {share}', f'oifname "eth0" {share}')

    def block_multicast(self) -> None:
        """The host neither sends nor receives multicast: discovery must find the other hosts by name
        (static peers, a discovery server)."""
        self._drop("dvmulticast", "ip daddr 224.0.0.0/4", "ip daddr 224.0.0.0/4")

    def rate(self, kbit: int | None) -> None:
        """The host sends at most ``kbit`` kilobits a second (a token bucket), or as fast as it can
        (None)."""
        _command(
            ["ip", "netns", "exec", self.netns, "tc", "qdisc", "del", "dev", "eth0", "root"], check=False
        )
        if kbit is not None:
            burst = max(kbit * 1000 // 8 // 10, 16_000)  # a tenth of a second's worth, at least 16 kB
            _command(
                [
                    "ip",
                    "netns",
                    "exec",
                    self.netns,
                    "tc",
                    "qdisc",
                    "add",
                    "dev",
                    "eth0",
                    "root",
                    "tbf",
                    "rate",
                    f"{kbit}kbit",
                    "burst",
                    str(burst),
                    "latency",
                    "400ms",
                ]
            )

    def counters(self) -> dict[str, int]:
        """The link's packet and byte counters (what the host sent and received), from the kernel."""
        shown = _command(["ip", "-n", self.netns, "-s", "-j", "link", "show", "eth0"]).stdout
        stats = json.loads(shown)[0]["stats64"]
        return {
            "rx_bytes": stats["rx"]["bytes"],
            "rx_packets": stats["rx"]["packets"],
            "tx_bytes": stats["tx"]["bytes"],
            "tx_packets": stats["tx"]["packets"],
        }

    def close(self) -> None:
        """End every process started here that still runs (SIGTERM, then SIGKILL)."""
        for process in self.processes:
            process.stop(signal.SIGTERM)


class HostProcess:
    """A process on a host, its output read live into ``lines`` (standard error with standard output).

    Every wait is bounded and fails with the process's output, so that a failed run says what the
    process saw."""

    def __init__(
        self, host: Host, argv: list[str], env: Mapping[str, str] | None, *, stdin: bool = False
    ) -> None:
        self.host = host
        self.argv = argv
        self.lines: list[str] = []
        self.process = subprocess.Popen(
            argv,
            env=dict(env) if env is not None else None,
            stdout=subprocess.PIPE,
            stderr=subprocess.STDOUT,
            stdin=subprocess.PIPE if stdin else subprocess.DEVNULL,
            text=True,
            start_new_session=True,  # its children too are ended with it (a tool that starts a server)
        )
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self) -> None:
        assert self.process.stdout is not None
        for line in self.process.stdout:
            self.lines.append(line.rstrip("\n"))

    def __repr__(self) -> str:
        return f"<{' '.join(self.argv[4:])} on {self.host.name}>"

    def write(self, text: str) -> None:
        """Write ``text`` to the process's input (started with ``stdin``)."""
        assert self.process.stdin is not None, f"{self!r} was started without an input pipe"
        self.process.stdin.write(text)
        self.process.stdin.flush()

    @property
    def output(self) -> str:
        """Everything the process printed so far."""
        return "\n".join(self.lines)

    @property
    def returncode(self) -> int | None:
        """The exit status, or None while it runs."""
        return self.process.poll()

    def saw(self, text: str) -> bool:
        """A line so far holds ``text``."""
        return any(text in line for line in self.lines)

    def wait_line(self, text: str, timeout: float) -> str:
        """The first line holding ``text``, waited for at most ``timeout`` seconds; the test fails (with
        the output) if the process ends first or the time passes."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            for line in list(self.lines):
                if text in line:
                    return line
            if self.process.poll() is not None:
                self._reader.join(timeout=CLOSE_BOUND)
                if self.saw(text):
                    continue
                raise AssertionError(
                    f"{self!r} ended with {self.process.returncode} before printing {text!r}:\n{self.output}"
                )
            time.sleep(0.02)
        raise AssertionError(f"{self!r} did not print {text!r} within {timeout:g} s:\n{self.output}")

    def finish(self, timeout: float) -> int:
        """The exit status, once the process ends, at most ``timeout`` seconds (else it is killed and
        the test fails with its output)."""
        try:
            self.process.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self._signal(signal.SIGKILL)
            self.process.wait(timeout=CLOSE_BOUND)
            self._reader.join(timeout=CLOSE_BOUND)
            raise AssertionError(f"{self!r} did not end within {timeout:g} s:\n{self.output}") from None
        self._reader.join(timeout=CLOSE_BOUND)
        return self.process.returncode

    def _signal(self, signum: int) -> None:
        """Send ``signum`` to the process and every process it started (its session's group)."""
        with contextlib.suppress(ProcessLookupError):
            os.killpg(self.process.pid, signum)

    def kill(self) -> None:
        """``kill -9``: the process ends at once, saying nothing to anyone (and whatever it started)."""
        self._signal(signal.SIGKILL)
        self.process.wait(timeout=CLOSE_BOUND)
        self._reader.join(timeout=CLOSE_BOUND)

    def stop(self, signum: int = signal.SIGINT) -> int:
        """Send ``signum`` unless the process has ended; its exit status once it ends (SIGKILL after
        :data:`CLOSE_BOUND` seconds)."""
        if self.process.poll() is None:
            self.process.send_signal(signum)
        try:
            self.process.wait(timeout=CLOSE_BOUND)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait(timeout=CLOSE_BOUND)
        self._signal(signal.SIGKILL)  # whatever it started and left behind
        self._reader.join(timeout=CLOSE_BOUND)
        if self.process.stdout is not None:
            self.process.stdout.close()
        return self.process.returncode


class Site:
    """Hosts ``names`` on one bridge, in network namespaces of their own (see the module's docs)."""

    def __init__(self, names: Sequence[str]) -> None:
        if len(set(names)) != len(names) or not names:
            raise ValueError(f"a site's hosts need names of their own (got {list(names)})")
        remove_abandoned()
        self.tag = f"{PREFIX}{os.getpid()}s{next(_sites)}"
        self.bridge_netns = f"{self.tag}-bridge"
        self.hosts: dict[str, Host] = {}
        try:
            _ip("netns", "add", self.bridge_netns)
            _ip("-n", self.bridge_netns, "link", "add", "br0", "type", "bridge")
            _ip("-n", self.bridge_netns, "link", "set", "br0", "up")
            for index, name in enumerate(names):
                self._add(Host(self, name, index))
        except BaseException:
            self.close()
            raise

    def _add(self, host: Host) -> None:
        _ip("netns", "add", host.netns)
        self.hosts[host.name] = host
        _ip(
            "link",
            "add",
            "eth0",
            "netns",
            host.netns,
            "type",
            "veth",
            "peer",
            "name",
            host.port,
            "netns",
            self.bridge_netns,
        )
        _ip("-n", self.bridge_netns, "link", "set", host.port, "master", "br0", "up")
        _ip("-n", host.netns, "addr", "add", f"{host.address}/{SUBNET.prefixlen}", "dev", "eth0")
        _ip("-n", host.netns, "link", "set", "eth0", "up")
        _ip("-n", host.netns, "link", "set", "lo", "up")
        # multicast (DDS discovery) leaves by the site's link; nothing else has a route out
        _ip("-n", host.netns, "route", "add", "224.0.0.0/4", "dev", "eth0")

    def __getitem__(self, name: str) -> Host:
        return self.hosts[name]

    def addresses(self) -> list[str]:
        """Every host's address, in the order the hosts were named."""
        return [host.address for host in self.hosts.values()]

    def close(self) -> None:
        """End every host's processes, then remove the namespaces (the links go with them)."""
        for host in self.hosts.values():
            host.close()
        for host in self.hosts.values():
            _ip("netns", "delete", host.netns, check=False)
        _ip("netns", "delete", self.bridge_netns, check=False)

    def __enter__(self) -> Site:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
