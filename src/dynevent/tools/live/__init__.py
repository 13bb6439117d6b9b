"""The commands on a live ROS 2 graph, over the ROS binding (:mod:`dynevent.ros`): ``dynevent serve``
(:mod:`~dynevent.tools.live.serve`), ``send`` (:mod:`~dynevent.tools.live.send`), ``record``
(:mod:`~dynevent.tools.live.record`) and ``probe`` (:mod:`~dynevent.tools.live.probe`).  Each module
needs ROS 2 to import; the command line checks a command's own input before it imports one.
"""

from __future__ import annotations

import os

__all__ = ["see_the_whole_graph"]


def see_the_whole_graph() -> None:
    """Before a command's ROS 2 session: through a Fast DDS discovery server (``ROS_DISCOVERY_SERVER``)
    a participant learns only the endpoints it matches, so a command that reads the graph (``send``
    and ``probe`` name the servers it has when the robot is not there, ``record`` finds the topics to
    record on it) would see nothing and wait to its timeout; its participant is made a super client
    (``ROS_SUPER_CLIENT``), which learns them all, unless the environment says otherwise."""
    if os.environ.get("ROS_DISCOVERY_SERVER", "").strip():
        os.environ.setdefault("ROS_SUPER_CLIENT", "TRUE")
