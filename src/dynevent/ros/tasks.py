"""A robot's task told to a running ``dynevent serve`` (:mod:`dynevent.ros.fleet`) from outside: the
serve nodes on the graph, their parameters read and set through their parameter services, and the
begin message published (``dynevent task``: :mod:`dynevent.tools.live.task`)."""

from __future__ import annotations

import re
import threading
import time
from typing import Any

from rclpy.duration import Duration
from rclpy.parameter import Parameter
from rclpy.parameter_client import AsyncParameterClient

from dynevent.ros.convert import RosDescription
from dynevent.ros.fleet import BEGIN_COMMAND_TOPIC, serve_node_name
from dynevent.ros.qos import latched

__all__ = ["RETRY", "ParameterLink", "publish_begin", "serve_nodes"]

#: How long a parameter request waits for its answer before it is sent again (seconds): a response to
#: a client the server has not matched yet is lost (found with two probes at once, 30 robots served).
RETRY = 1.0

#: A serve node of any fleet (not its lanes' other nodes, nor its judge's).
_ANY_SERVE = r"dynevent_serve_(?!.*_(lane_\d+|judge)$)\w+"


def serve_nodes(node: Any, fleet: str | None = None) -> list[str]:
    """The full names of the nodes of serve processes (of ``fleet``, or any) that hold their robots'
    parameters (:func:`~dynevent.ros.fleet.serve_node_name`), as ``node`` sees the graph, sorted."""
    named = re.compile(re.escape(serve_node_name(fleet)) + r"(_\d+_of_\d+)?" if fleet else _ANY_SERVE)
    names = node.get_node_names_and_namespaces()
    return sorted(f"{space.rstrip('/')}/{name}" for name, space in set(names) if named.fullmatch(name))


class ParameterLink:
    """The parameters of the node ``remote`` from ``node`` (spun by its caller), each call bounded."""

    def __init__(self, node: Any, remote: str) -> None:
        self._client = AsyncParameterClient(node, remote)

    def ask(self, names: list[str]) -> Any:
        """A request for the values of ``names`` (a future of a GetParameters response: a value's ``type``
        0 for one not declared), or None while the node's services are not matched."""
        return self._client.get_parameters(names) if self._client.services_are_ready() else None

    def set(self, name: str, value: bool, within: float) -> str | None:
        """Set ``name``: None when no answer came, else ``""`` or the node's reason for refusing; sent
        again each :data:`RETRY` s until one is answered (a set is idempotent)."""
        deadline = time.monotonic() + within
        if not self._client.wait_for_services(timeout_sec=within):
            return None
        sent: list[Any] = []
        while time.monotonic() < deadline:
            sent.append(self._client.set_parameters([Parameter(name, value=value)]))
            reply = _first_result(sent, min(time.monotonic() + RETRY, deadline))
            if reply is not None:
                return "" if reply.results[0].successful else str(reply.results[0].reason)
        return None


def publish_begin(node: Any, fleet: str, robot: str, description: str, within: float) -> bool:
    """Publish the begin message once a subscription is matched; whether all acknowledged it in time."""
    publisher = node.create_publisher(RosDescription, BEGIN_COMMAND_TOPIC, latched(1))
    deadline = time.monotonic() + within
    while publisher.get_subscription_count() == 0 and time.monotonic() < deadline:
        time.sleep(0.05)
    message = RosDescription()
    message.fleet, message.robot, message.description = fleet, robot, description
    publisher.publish(message)
    left = max(deadline - time.monotonic(), 0.0)
    return bool(publisher.wait_for_all_acked(Duration(nanoseconds=int(left * 1e9))))


def _first_result(futures: list[Any], deadline: float) -> Any:
    """The result of the first of ``futures`` done, or None at ``deadline`` (the node spun elsewhere)."""
    done = threading.Event()
    for future in futures:
        future.add_done_callback(lambda _future: done.set())
    done.wait(max(deadline - time.monotonic(), 0.0))
    return next((future.result() for future in futures if future.done()), None)
