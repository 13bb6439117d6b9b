"""``dynevent explain``: read a status and a goal from the command line, print what the machine says.

The judging is :func:`dynevent.conformance.explain.explain`; this module reads its arguments (inline
JSON, ``-`` for standard input, ``@FILE``), bounded in size, and prints the explanation as text or
JSON.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

from dynevent import files
from dynevent.conformance.explain import explain, format_explanation
from dynevent.errors import DyneventError, FileError, InvalidMessage, shown_path
from dynevent.wire import _json
from dynevent.wire.messages import DynamicEventStatus, Goal

__all__ = ["MAX_INPUT_BYTES", "run"]


class _ArgumentError(DyneventError):
    def __init__(self, argument: str, problem: str) -> None:
        super().__init__(f"{argument}: {problem}")


#: The most JSON ``explain`` reads from a file or standard input (a status or a goal is far smaller).
MAX_INPUT_BYTES = 4_000_000


def _json_text(argument: str, value: str, stdin_taken: list[str]) -> str:
    """The JSON text an argument names: inline, ``-`` for standard input, or ``@FILE``."""
    if value == "-":
        if stdin_taken:
            raise _ArgumentError(argument, f"standard input is already read for {stdin_taken[0]}")
        stdin_taken.append(argument)
        return _bounded(argument, "standard input", sys.stdin.buffer.read(MAX_INPUT_BYTES + 1))
    if value.startswith("@"):
        path = value[1:]
        try:
            return _bounded(argument, path, files.read_bytes(path, argument, limit=MAX_INPUT_BYTES + 1))
        except FileError as exc:
            raise _ArgumentError(argument, f"{shown_path(path)} {exc.problem}") from None
    return value


def _bounded(argument: str, source: str, data: bytes) -> str:
    if len(data) > MAX_INPUT_BYTES:
        raise _ArgumentError(argument, f"{source} holds more than {MAX_INPUT_BYTES:,} bytes")
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise _ArgumentError(argument, f"{source} is not UTF-8 (byte {exc.start})") from None


def _parse_message(argument: str, cls: type[Any], text: str) -> Any:
    try:
        return cls.from_json(text)
    except InvalidMessage as exc:
        raise _ArgumentError(argument, str(exc)) from None


def _parse_categories(text: str | None) -> tuple[str, ...] | None:
    if text is None:
        return None
    names = tuple(name.strip() for name in text.split(","))
    if any(not name for name in names):
        raise _ArgumentError("--categories", f"an empty category name in {text!r}")
    return names


def run(args: argparse.Namespace) -> int:
    """``dynevent explain``: say whether the robot accepts the goal; 0 accepted, 1 refused, 2 bad input."""
    try:
        stdin_taken: list[str] = []
        status = _parse_message(
            "--status", DynamicEventStatus, _json_text("--status", args.status, stdin_taken)
        )
        goal = _parse_message("--goal", Goal, _json_text("--goal", args.goal, stdin_taken))
        categories = _parse_categories(args.categories)
    except _ArgumentError as exc:
        print(f"dynevent explain: {exc}", file=sys.stderr)
        return 2
    explanation = explain(status, goal, categories=categories, compatibility=args.compatibility)
    if args.json:
        print(_json.dumps(explanation.to_dict()))
    else:
        print(format_explanation(explanation), end="")
    return 0 if explanation.accepted else 1
