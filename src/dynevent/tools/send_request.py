"""``dynevent send``'s goal, read from its flags without ROS 2.

So that ``dynevent send`` checks its own input, and says what is wrong with
it, before it needs rclpy.
"""

from __future__ import annotations

import argparse
import json

from dynevent import files
from dynevent.errors import FileError, SendError, short_repr
from dynevent.wire import _json
from dynevent.wire.vocab import EventType

__all__ = ["goal_request"]


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
