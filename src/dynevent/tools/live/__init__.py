"""The commands on a live ROS 2 graph, over the ROS binding (:mod:`dynevent.ros`): ``dynevent serve``
(:mod:`~dynevent.tools.live.serve`), ``send`` (:mod:`~dynevent.tools.live.send`), ``record``
(:mod:`~dynevent.tools.live.record`) and ``probe`` (:mod:`~dynevent.tools.live.probe`).  Each module
needs ROS 2 to import; a command (:mod:`dynevent.tools.serve`, ``send``, ``record``, ``probe``) checks
its own input before it imports one, through :func:`run_over_ros`.
"""

from __future__ import annotations

import contextlib
import importlib
import importlib.util
import os
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar

__all__ = ["OFFLINE", "body", "flush_output", "offline", "run_over_ros", "say", "see_the_whole_graph"]

T = TypeVar("T")

#: What a command says when it starts with no network but loopback while DDS may look beyond the host.
OFFLINE = (
    "no network interface but loopback is up: DDS (Fast DDS) takes the interfaces that are up when a "
    "process starts, so this one will not reach other hosts when the network comes up; start it once "
    "the network is up"
)


def flush_output() -> None:
    """Flush what the command printed, before its ROS close-down: a close-down its bound ends
    (:func:`dynevent.ros.spinning.bounded_close`) ends the process without flushing Python's buffers,
    and a report still in them is lost (found in CI: a probe's)."""
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(OSError, ValueError, AttributeError):  # closed, or a closed pipe's
            stream.flush()


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


def say(line: str) -> None:
    """Print one whole line at once: the live logs print from several threads."""
    sys.stdout.write(line + "\n")
    sys.stdout.flush()


def body(command: str) -> Any:
    """``dynevent.tools.live.<command>`` (over the ROS binding), or None after two lines on standard
    error: what is missing, and how to get it (the setup script ships in the package:
    ``dynevent/ros/setup/setup-ros-env.sh``)."""
    try:
        return importlib.import_module(f"dynevent.tools.live.{command}")
    except ImportError as exc:
        missing = (exc.name or "rclpy").split(".")[0]  # the package to install, not its submodule
        if missing != "rclpy" and importlib.util.find_spec("rclpy") is None:
            missing = "rclpy"  # the root of what is missing, whichever ROS package was imported first
        script = Path(__file__).resolve().parents[2] / "ros" / "setup" / "setup-ros-env.sh"
        print(
            f"dynevent {command}: needs ROS 2 (rclpy, rmf_task_msgs); {missing} is not importable",
            file=sys.stderr,
        )
        out = Path.cwd() / "build" / "ros"
        print(
            f"  get it, into this environment: bash {script} {sys.prefix} {out} && . {out}/env.sh",
            file=sys.stderr,
        )
        return None


def run_over_ros(command: str, check: Callable[[], T], run: Callable[[Any, T], int]) -> int:
    """A command over ROS 2: ``check()`` its own input first (a mistake there needs no ROS to be told),
    then ``run(module, checked)`` with ``dynevent.tools.live.<command>`` (:func:`body`); a
    :class:`~dynevent.errors.DyneventError` is one line, exit 2."""
    from dynevent.errors import DyneventError

    try:
        checked = check()
        module = body(command)
        return 2 if module is None else int(run(module, checked))
    except DyneventError as exc:
        print(f"dynevent {command}: {exc}", file=sys.stderr)
        return 2
