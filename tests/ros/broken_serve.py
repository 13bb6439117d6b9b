"""``dynevent serve`` with one deliberate defect, for the probe to catch (tests/ros/test_ros_probe.py).

``python broken_serve.py DEFECT SERVE-ARGS...``: each defect is one of the test kit's
(:data:`dynevent.testing.broken.DEFECTS`: the same the in-process probe meets), put in the real
server of this process only, or ``volatile_status``, which only a transport has.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from typing import Any

from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from dynevent.ros import qos as ros_qos
from dynevent.ros import server as ros_server
from dynevent.server import machine
from dynevent.server import outputs as outs
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


INSTALL: dict[str, Callable[[], None]] = {name: _install(name) for name in DEFECTS}
INSTALL["volatile_status"] = _volatile_topics

if __name__ == "__main__":
    INSTALL[sys.argv[1]]()
    sys.exit(main(["serve", *sys.argv[2:]]))
