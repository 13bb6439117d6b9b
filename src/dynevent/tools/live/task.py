"""``dynevent task``: tell a running ``dynevent serve`` what happens to one robot's task around its
dynamic event, over the ROS binding (:class:`dynevent.ros.tasks.ServeTasks`): ``begin`` a dynamic
event (R3), ``interrupt`` the task (R14.1, R14.2: a NEXT's child that starts while it is interrupted
waits, R6.3), ``resume`` it (R14.3 to R14.5).  An interrupt or resume is a set of the robot's
``interrupted.<robot>`` parameter on the node of the shard that serves it, which answers once the
server took it: when the command has ended, the next goal meets the task as it was told.

Everything is bounded by ``--timeout``.  Exit status: 0 once the serve took it, 1 when it refused
or did not answer, 2 on bad usage or when no serve of the robot was found.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from typing import Any

import attrs

from dynevent.ros.fleet import FLEET, INTERRUPTED
from dynevent.ros.spinning import Session
from dynevent.ros.tasks import RETRY, ParameterLink, publish_begin, serve_nodes
from dynevent.tools.live import flush_output, offline, see_the_whole_graph

__all__ = ["ServeTasks", "TaskOptions", "run"]


@attrs.frozen(kw_only=True)
class TaskOptions:
    """What ``dynevent task`` is asked to do, its flags read and checked by the command line."""

    fleet: str
    robot: str
    what: str  # "begin", "interrupt" or "resume"
    description: str = ""  # a begin's, JSON text (the serve's default when empty)
    timeout: float = 10.0  # the bound on the whole command, in seconds
    ros_args: tuple[str, ...] = ()  # ROS 2's own command-line arguments (``--ros-args ...``)


def run(options: TaskOptions, say: Callable[[str], None]) -> int:
    """Tell the serve; 0, 1 or 2 as the module docs say."""
    deadline = time.monotonic() + options.timeout
    robot = f"{options.fleet}/{options.robot}"
    see_the_whole_graph()
    offline(say)
    session = Session("dynevent_task", options.ros_args)
    session.start()
    try:
        tasks = ServeTasks(session.node, options.fleet, options.robot)
        serve_node = tasks.find(options.timeout)
        if serve_node is None:
            seen = ", ".join(serve_nodes(session.node)) or "none"
            say(f"no dynevent serve of {robot} within {options.timeout:g} s (serve nodes seen: {seen})")
            return 2
        left = max(deadline - time.monotonic(), 0.0)
        if options.what == "begin":
            why = tasks.begin(options.description, left)
        else:
            why = tasks.set_interrupted(serve_node, options.what == "interrupt", left)
        if why:
            say(f"{robot}: {options.what} not taken: {why}")
            return 1
        taken = {"begin": "a dynamic event asked to begin", "interrupt": "the task interrupted"}
        say(f"{robot}: {taken.get(options.what, 'the task resumed')} ({serve_node})")
        return 0
    finally:
        flush_output()
        session.close()


#: How long after a serve node said it does not serve the robot it is asked again (seconds): one
#: that starts declares its robots' parameters one by one.
WAKE = 0.5
#: How often the graph and the answers are looked at while the robot's serve is looked for (seconds).
POLL = 0.05

#: The type of a bool parameter's value (rcl_interfaces ParameterType.PARAMETER_BOOL).
_BOOL = 1


class ServeTasks:
    """Tell the ``dynevent serve`` of ``fleet`` that serves ``robot`` what happens to its task, from
    ``node`` (spun by its caller); every call is bounded by the seconds it is given."""

    def __init__(self, node: Any, fleet: str, robot: str) -> None:
        self._node = node
        self.fleet = fleet
        self.robot = robot
        self._links: dict[str, ParameterLink] = {}

    def find(self, within: float) -> str | None:
        """The full name of the serve node that serves the robot, looked for up to ``within`` s: the
        one whose parameters name the fleet and the robot.  Each serve node of the fleet on the graph
        is asked, again :data:`WAKE` s after it said no, and :data:`~dynevent.ros.tasks.RETRY` s after
        a request it has not answered (a response can be lost, or come late from a loaded serve: every
        request sent is waited for)."""
        deadline = time.monotonic() + within
        asked: dict[str, list[tuple[float, Any]]] = {}
        names = [FLEET, f"{INTERRUPTED}.{self.robot}"]
        while True:
            now = time.monotonic()
            for name in serve_nodes(self._node, self.fleet):
                requests = asked.setdefault(name, [])
                for _, future in requests:
                    reply = future.result() if future.done() else None  # None too for one cancelled
                    values: list[Any] = list(reply.values) if reply is not None else []
                    if len(values) == 2 and values[0].string_value == self.fleet and values[1].type == _BOOL:
                        return name
                last, future = requests[-1] if requests else (0.0, None)
                if now - last >= (WAKE if future is None or future.done() else RETRY):
                    ask = self._link(name).ask(names)
                    if ask is not None:
                        requests.append((now, ask))
            if now >= deadline:
                return None
            time.sleep(min(POLL, max(deadline - now, 0.0)))

    def set_interrupted(self, serve_node: str, value: bool, within: float) -> str:
        """Interrupt (``value``) or resume the robot's task: ``""`` once ``serve_node`` took it, else
        why not."""
        name = f"{INTERRUPTED}.{self.robot}"
        refused = self._link(serve_node).set(name, value, within)
        if refused is None:
            return f"{serve_node} did not answer the set of {name} within {within:g} s"
        return f"{serve_node} refused the set of {name}: {refused}" if refused else ""

    def begin(self, description: str, within: float) -> str:
        """Ask for a dynamic event to begin (``description`` its JSON text): ``""`` once every serve
        on the graph acknowledged the message, else why not."""
        if publish_begin(self._node, self.fleet, self.robot, description, within):
            return ""
        return f"the begin message was not acknowledged within {within:g} s"

    def _link(self, serve_node: str) -> ParameterLink:
        if serve_node not in self._links:
            self._links[serve_node] = ParameterLink(self._node, serve_node)
        return self._links[serve_node]
