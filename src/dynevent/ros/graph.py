"""What the ROS graph shows of Dynamic Event servers: which robots serve the action, so that a command
pointed at a name no server has can say which names it does see."""

from __future__ import annotations

from typing import Any

from rclpy.action import get_action_server_names_and_types_by_node

from dynevent.errors import InvalidName
from dynevent.wire.names import NameKind, parse_name

__all__ = ["graph_text", "no_server_text", "servers_seen"]


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
    return f"no Dynamic Event server for {fleet}/{robot} within {waited:g} s; {graph_text(node)}"


def graph_text(node: Any) -> str:
    """What the graph has: every fleet, each with its count of robots and the first few names."""
    seen = servers_seen(node)
    if not seen:
        return "no Dynamic Event server is on the graph (ROS_DOMAIN_ID and the discovery range must match)"
    fleets: dict[str, list[str]] = {}
    for fleet, robot in seen:
        fleets.setdefault(fleet, []).append(robot)
    listed = []
    for fleet, robots in fleets.items():
        first = ", ".join(robots[:_NAMED])
        more = f", ... ({len(robots) - _NAMED} more)" if len(robots) > _NAMED else ""
        listed.append(f"fleet {fleet}: {len(robots)} robot(s) ({first}{more})")
    return "the graph has " + "; ".join(listed)


#: The robots named of each fleet the graph has (the rest are counted).
_NAMED = 5
