"""``dynevent send``: its goal read from its flags without ROS 2 (so that a mistake there is told
before rclpy is needed), then sent over it (:mod:`dynevent.tools.live.send`)."""

from __future__ import annotations

import argparse
import json
from typing import Any

from dynevent import files
from dynevent.errors import FileError, SendError, short_repr
from dynevent.tools.live import run_over_ros, say
from dynevent.wire import _json
from dynevent.wire.vocab import EventType

__all__ = ["goal_request", "run"]


def run(args: argparse.Namespace) -> int:
    """``dynevent send``: send the goal and print what becomes of it; 0 it succeeded, 1 it did not, 2 bad
    usage or no server."""

    def check() -> tuple[EventType, str, str]:
        if not 0 < args.timeout < 1e6:
            raise SendError(f"--timeout: expected positive seconds (got {args.timeout})")
        files.check_writable(args.trace, "--trace")
        return goal_request(args)

    def send(live: Any, goal: tuple[EventType, str, str]) -> int:
        event_type, category, description = goal
        options = live.SendOptions(
            fleet=args.fleet, robot=args.robot, event_type=event_type, category=category,
            description=description, stubborn_period=args.stubbornness, timeout=args.timeout,
            trace=args.trace, introspection=args.introspection, wait=args.wait, ros_args=tuple(args.ros_args),
        )  # fmt: skip
        return int(live.run(options, say))

    return run_over_ros("send", check, send)


def goal_request(args: argparse.Namespace) -> tuple[EventType, str, str]:
    """The goal the flags ask for: (event type, category, description)."""
    chosen = [name for name in ("place", "cancel", "end", "file", "description") if getattr(args, name, None)]
    if len(chosen) != 1:
        raise SendError("give exactly one of --place, --cancel, --end, --file, --description")
    if args.place:
        return EventType.NEXT, "go_to_place", json.dumps({"one_of": list(args.place)})
    if args.description:
        return EventType.NEXT, args.category, _description(args.description)
    if args.cancel:
        return EventType.CANCEL, "", ""
    if args.end:
        return EventType.FINISHED, "", ""
    try:
        data = files.read_json(args.file, "--file")
    except FileError as exc:
        raise SendError(str(exc)) from None
    if not isinstance(data, dict) or not isinstance(data.get("category"), str) or "description" not in data:
        raise SendError(f'--file {args.file}: expected {{"category": "...", "description": ...}}')
    description = data["description"]
    return (
        EventType.NEXT,
        data["category"],
        description if isinstance(description, str) else json.dumps(description),
    )


def _description(text: str) -> str:
    """``--description``'s JSON text (``@FILE``: the file's), checked to be JSON."""
    source = "--description"
    if text.startswith("@"):
        source = f"--description {short_repr(text)}"
        try:
            text = files.read_text(text[1:], "--description")
        except FileError as exc:
            raise SendError(str(exc)) from None
    try:
        _json.parse(text)
    except _json.JsonProblem as exc:
        raise SendError(f"{source}: not JSON dynevent reads: {exc}") from None
    return text.strip()
