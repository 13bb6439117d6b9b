"""A ROS 2 site on the test bed's hosts: every process of it in one DDS domain, finding the others in
one of three ways, as sites do.

- ``multicast``: DDS's own discovery, by multicast on the hosts' subnet
  (``ROS_AUTOMATIC_DISCOVERY_RANGE=SUBNET``, ROS 2's default);
- ``static_peers``: multicast blocked on every host (as between subnets, in many clouds and VPNs),
  and every process given every host's address (``ROS_STATIC_PEERS``);
- ``discovery_server``: multicast blocked, a Fast DDS discovery server (``fastdds discovery``) on
  the site's first host, and every process pointed at it (``ROS_DISCOVERY_SERVER``).

DDS runs with its defaults otherwise (a participant's lease: 20 s).  Hosts on one machine share its
memory, but Fast DDS takes processes in two network namespaces for two hosts: a partition of a host
cuts everything DDS carries to it (test_ros_contact.py shows it).
"""

from __future__ import annotations

import json
import os
import sys
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from hosts import Host, HostProcess, Site

#: The ways a site's processes find each other.
MODES = ("multicast", "static_peers", "discovery_server")
#: The DDS domain of every site (sites never meet: each has a network of its own).
DOMAIN = 42
#: The discovery server's port.
DISCOVERY_PORT = 11811
#: The bound on a process's start (a Python interpreter importing rclpy, on a loaded machine), seconds.
START = 60.0


class RosSite:
    """A :class:`hosts.Site` whose processes speak ROS 2 in one DDS domain, discovering each other in
    ``mode`` (one of :data:`MODES`); ``folder`` holds its files (configurations, bags, traces)."""

    def __init__(self, site: Site, mode: str, folder: Path) -> None:
        if mode not in MODES:
            raise ValueError(f"mode: one of {MODES} (got {mode!r})")
        self.site, self.mode, self.folder = site, mode, folder
        folder.mkdir(parents=True, exist_ok=True)
        env = {key: value for key, value in os.environ.items() if not key.startswith(("ROS_", "FASTDDS_"))}
        env.update(PYTHONFAULTHANDLER="1", PYTHONUNBUFFERED="1", ROS_DOMAIN_ID=str(DOMAIN))
        env.update(ROS_AUTOMATIC_DISCOVERY_RANGE="SUBNET")
        if mode != "multicast":
            for host in site.hosts.values():
                host.block_multicast()
        if mode == "static_peers":
            env["ROS_STATIC_PEERS"] = ";".join(site.addresses())
        self.discovery: HostProcess | None = None
        if mode == "discovery_server":
            server = next(iter(site.hosts.values()))
            self.discovery = server.start(
                ["fastdds", "discovery", "-i", "0", "-l", server.address, "-p", str(DISCOVERY_PORT)], env
            )
            self.discovery.wait_line("Server started", START)
            env["ROS_DISCOVERY_SERVER"] = f"{server.address}:{DISCOVERY_PORT}"
        self.env: Mapping[str, str] = env

    def __getitem__(self, name: str) -> Host:
        return self.site[name]

    def dynevent(self, host: str, *args: str, env: Mapping[str, str] | None = None) -> HostProcess:
        """``dynevent ARGS`` started on ``host``, in the site's environment (and ``env``)."""
        return self.site[host].start([sys.executable, "-m", "dynevent", *args], {**self.env, **(env or {})})

    def python(
        self, host: str, *args: str, env: Mapping[str, str] | None = None, stdin: bool = False
    ) -> HostProcess:
        """``python ARGS`` started on ``host``, in the site's environment (and ``env``)."""
        return self.site[host].start([sys.executable, *args], {**self.env, **(env or {})}, stdin=stdin)

    def file(self, name: str, content: Any) -> Path:
        """A file of the site's folder holding ``content`` (JSON unless it is text)."""
        path = self.folder / name
        path.write_text(content if isinstance(content, str) else json.dumps(content), encoding="utf-8")
        return path

    def serve(
        self, host: str, robots: Sequence[str], categories: Mapping[str, Any], *args: str
    ) -> HostProcess:
        """``dynevent serve`` of ``robots`` on ``host`` with these simulated categories, once it serves."""
        config = self.file(
            f"fleet-{host}.json", {"robots": list(robots), "rebegin": 0, "categories": categories}
        )
        serve = self.dynevent(host, "serve", "--config", str(config), *args)
        serve.wait_line("serving ", START)
        return serve

    def close(self) -> None:
        """Remove the site (its processes end with it); what each process printed is kept in the
        site's folder (``<host>-<n>.log``, in the order started), so that a failed run can be read."""
        try:
            self.site.close()
        finally:
            for host in self.site.hosts.values():
                for number, process in enumerate(host.processes):
                    lines = [" ".join(process.argv[4:]), *list(process.lines)]
                    (self.folder / f"{host.name}-{number}.log").write_text("\n".join(lines) + "\n", "utf-8")
