"""``dynevent serve`` with one deliberate defect, for the probe to catch (tests/ros/test_ros_probe.py).

``python broken_serve.py DEFECT SERVE-ARGS...``: each defect is one of the test kit's
(:data:`dynevent.testing.broken.DEFECTS`: the same the in-process probe meets), put in the real
server of this process only, or ``volatile_status``, which only a transport has, or
``faulty_callback`` (the robot ``faulty`` raises in a callback).

``python broken_serve.py switched_off ROBOT=RULE,... SERVE-ARGS...``: each robot named served with
that one check of the machine switched off (the test kit's :mod:`dynevent.testing.switched_off`),
the robots given to serve as ``--robot`` (tests/ros/test_ros_completeness.py).
"""

from __future__ import annotations

import contextlib
import sys
import threading
from collections.abc import Callable, Mapping
from typing import Any

from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from dynevent.ros import qos as ros_qos
from dynevent.ros import server as ros_server
from dynevent.server import machine
from dynevent.server import outputs as outs
from dynevent.testing import switched_off as kit
from dynevent.testing.broken import DEFECTS, Rewrite
from dynevent.tools.cli import main


def _volatile_topics() -> None:
    """The status and begin topics are published volatile, not transient-local (R1.4): a late
    subscriber gets nothing, and one that asks for transient-local (as R1.4 has clients do) never
    matches them."""

    def volatile(depth: int) -> QoSProfile:
        return QoSProfile(
            history=HistoryPolicy.KEEP_LAST, depth=depth, reliability=ReliabilityPolicy.RELIABLE,
            durability=DurabilityPolicy.VOLATILE,
        )  # fmt: skip

    ros_qos.latched = volatile  # what the server's publishers are made with


def _rewrite(change: Rewrite) -> None:
    """Each output goes through ``change`` before the server carries it out (None: dropped)."""
    original = ros_server.DynamicEventServer._carry_out
    notes: dict[str, Any] = {}

    def carry_out(self: Any, output: outs.Output) -> None:
        types = {uuid: int(handle.request.event_type) for uuid, handle in self._handles.items()}
        changed = change(types, notes, output)
        if changed is not None:
            original(self, changed)
        for after in notes.pop("after", ()):
            original(self, after)

    ros_server.DynamicEventServer._carry_out = carry_out  # type: ignore[method-assign]


def _install(name: str) -> Callable[[], None]:
    defect = DEFECTS[name]

    def install() -> None:
        for function, replacement in defect.patches.items():
            setattr(machine, function, replacement)
        if defect.rewrite is not None:
            _rewrite(defect.rewrite)

    return install


def _faulty_callback() -> None:
    """The server of the robot named ``faulty`` raises where it starts a child, inside the executor's
    callback that carries the step out: one robot's fault, which the robots of its lane must outlive."""
    made, carry_out = ros_server.DynamicEventServer.__init__, ros_server.DynamicEventServer._carry_out

    def init(self: Any, node: Any, fleet: str, robot: str, *args: Any, **kwargs: Any) -> None:
        made(self, node, fleet, robot, *args, **kwargs)
        self.faulty = robot == "faulty"

    def faulty_carry_out(self: Any, output: outs.Output) -> None:
        if self.faulty and isinstance(output, outs.StartChild):
            raise RuntimeError("a deliberate fault")
        carry_out(self, output)

    ros_server.DynamicEventServer.__init__ = init  # type: ignore[method-assign]
    ros_server.DynamicEventServer._carry_out = faulty_carry_out  # type: ignore[method-assign]


INSTALL: dict[str, Callable[[], None]] = {name: _install(name) for name in DEFECTS}
INSTALL["volatile_status"] = _volatile_topics
INSTALL["faulty_callback"] = _faulty_callback


class _SwitchedOffLock:
    """A robot's server lock (under which the server does everything it asks of the machine) that,
    while held, holds the robot's check switched off.  A switch replaces the machine's module
    attributes, which every robot of the process shares: one robot at a time holds its switch."""

    _one_robot = threading.Lock()

    def __init__(self, rule: str) -> None:
        kit.switch(rule)  # a rule the machine does not carry out: KeyError now, not at the first step
        self._rule = rule
        self._held: list[contextlib.ExitStack] = []

    def __enter__(self) -> None:
        self._one_robot.acquire()
        with contextlib.ExitStack() as stack:  # released at once should the switch fail
            stack.callback(self._one_robot.release)
            stack.enter_context(kit.switched_off(self._rule))
            self._held.append(stack.pop_all())

    def __exit__(self, *exc: object) -> None:
        self._held.pop().close()


def _switch_off(rules: Mapping[str, str]) -> None:
    """The server of each robot of ``rules`` steps with its rule switched off, from its first step."""
    made = ros_server.DynamicEventServer.__init__

    def init(self: Any, node: Any, fleet: str, robot: str, *args: Any, **kwargs: Any) -> None:
        made(self, node, fleet, robot, *args, **kwargs)
        self._lock = _SwitchedOffLock(rules[robot])

    ros_server.DynamicEventServer.__init__ = init  # type: ignore[method-assign]


def _switched_off_serve(pairs: str, serve_args: list[str]) -> int:
    rules = dict(pair.split("=", 1) for pair in pairs.split(","))
    _switch_off(rules)
    robots = [word for robot in rules for word in ("--robot", robot)]
    return main(["serve", *robots, *serve_args])


if __name__ == "__main__":
    if sys.argv[1] == "switched_off":
        sys.exit(_switched_off_serve(sys.argv[2], sys.argv[3:]))
    INSTALL[sys.argv[1]]()
    sys.exit(main(["serve", *sys.argv[2:]]))
