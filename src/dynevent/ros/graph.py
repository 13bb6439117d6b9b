"""What the ROS graph shows of Dynamic Event servers: which robots serve the action, so that a command
pointed at a name no server has can say which names it does see."""

from __future__ import annotations

from typing import Any

from rclpy.action import get_action_server_names_and_types_by_node

from dynevent.errors import InvalidName
from dynevent.wire.names import NameKind, parse_name

__all__ = ["no_server_text", "servers_seen"]


def servers_seen(node: Any) -> list[tuple[str, str]]:
    """The (fleet, robot) of every Dynamic Event action server ``node`` sees on the graph, sorted."""
    seen = set()
    # by node, servers only: an action's name is on the graph as soon as any client of it is (this
    # process's own, say)
    for name, namespace in node.get_node_names_and_namespaces():
        try:
            served = get_action_server_names_and_types_by_node(node, name, namespace)
        except Exception:  # a node gone between the two calls
            continue
        for action, _types in served:
            try:
                parsed = parse_name(action)
            except InvalidName:
                continue  # another action
            if parsed.kind is NameKind.ACTION:
                seen.add((parsed.fleet, parsed.robot))
    return sorted(seen)


def no_server_text(node: Any, fleet: str, robot: str, waited: float) -> str:
    """One line for a robot whose server did not appear: what was waited for, and what the graph holds."""
    seen = servers_seen(node)
    if not seen:
        where = "no Dynamic Event server is on the graph (ROS_DOMAIN_ID and the discovery range must match)"
    else:
        listed = ", ".join(f"{name}/{other}" for name, other in seen[:10])
        more = f" and {len(seen) - 10} more" if len(seen) > 10 else ""
        where = f"the graph has {listed}{more}"
    return f"no Dynamic Event server for {fleet}/{robot} within {waited:g} s; {where}"
