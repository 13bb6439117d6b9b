"""The commands on a live ROS 2 graph, over the ROS binding (:mod:`dynevent.ros`): ``dynevent serve``
(:mod:`~dynevent.tools.live.serve`), ``send`` (:mod:`~dynevent.tools.live.send`), ``record``
(:mod:`~dynevent.tools.live.record`) and ``probe`` (:mod:`~dynevent.tools.live.probe`).  Each module
needs ROS 2 to import; the command line checks a command's own input before it imports one.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

__all__ = ["OFFLINE", "offline", "see_the_whole_graph"]

#: What a command says when it starts with no network but loopback while DDS may look beyond the host.
OFFLINE = (
    "no network interface but loopback is up: DDS (Fast DDS) takes the interfaces that are up when a "
    "process starts, so this one will not reach other hosts when the network comes up; start it once "
    "the network is up"
)


def offline(say: Callable[[str], None], interfaces: Path = Path("/sys/class/net")) -> bool:
    """Before a command's ROS 2 session: say :data:`OFFLINE` (and True) when DDS may look beyond this
    host (``ROS_AUTOMATIC_DISCOVERY_RANGE`` is not ``LOCALHOST``) and no interface but loopback is
    up (Linux's ``/sys/class/net``; elsewhere nothing is said).  A robot's server started before its
    Wi-Fi came up is never found from another host (tests/net)."""
    if os.environ.get("ROS_AUTOMATIC_DISCOVERY_RANGE", "").strip().upper() == "LOCALHOST":
        return False
    try:
        names = [path.name for path in interfaces.iterdir() if path.name != "lo"]
        states = [(interfaces / name / "operstate").read_text(encoding="ascii").strip() for name in names]
    except OSError:
        return False
    if any(state in ("up", "unknown") for state in states):  # "unknown": a link without carrier sense
        return False
    say(OFFLINE)
    return True


def see_the_whole_graph() -> None:
    """Before a command's ROS 2 session: through a Fast DDS discovery server (``ROS_DISCOVERY_SERVER``)
    a participant learns only the endpoints it matches, so a command that reads the graph (``send``
    and ``probe`` name the servers it has when the robot is not there, ``record`` finds the topics to
    record on it) would see nothing and wait to its timeout; its participant is made a super client
    (``ROS_SUPER_CLIENT``), which learns them all, unless the environment says otherwise."""
    if os.environ.get("ROS_DISCOVERY_SERVER", "").strip():
        os.environ.setdefault("ROS_SUPER_CLIENT", "TRUE")
