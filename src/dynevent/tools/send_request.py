"""``dynevent send``'s goal, read from its flags without ROS 2.

So that ``dynevent send`` checks its own input, and says what is wrong with
it, before it needs rclpy.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from dynevent.errors import SendError
from dynevent.wire.vocab import EventType

__all__ = ["goal_request"]


def goal_request(args: argparse.Namespace) -> tuple[EventType, str, str]:
    """The goal the flags ask for: (event type, category, description)."""
    chosen = [name for name in ("place", "cancel", "end", "file") if getattr(args, name)]
    if len(chosen) != 1:
        raise SendError("give exactly one of --place, --cancel, --end, --file")
    if args.place:
        return EventType.NEXT, "go_to_place", json.dumps({"one_of": list(args.place)})
    if args.cancel:
        return EventType.CANCEL, "", ""
    if args.end:
        return EventType.FINISHED, "", ""
    try:
        data = json.loads(Path(args.file).read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        raise SendError(f"--file {args.file}: {exc}") from None
    if not isinstance(data, dict) or not isinstance(data.get("category"), str) or "description" not in data:
        raise SendError(f'--file {args.file}: expected {{"category": "...", "description": ...}}')
    description = data["description"]
    return (
        EventType.NEXT,
        data["category"],
        description if isinstance(description, str) else json.dumps(description),
    )
