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


def _description(text: str) -> str:
    """``--description``'s JSON text (``@FILE``: the file's), checked to be JSON."""
    source = "--description"
    if text.startswith("@"):
        source = f"--description {text}"
        try:
            text = Path(text[1:]).read_text(encoding="utf-8")
        except OSError as exc:
            raise SendError(f"{source}: {exc}") from None
    try:
        json.loads(text)
    except ValueError as exc:
        raise SendError(f"{source}: not JSON: {exc}") from None
    return text.strip()
