"""The ``dynevent`` command line."""

from __future__ import annotations

import argparse
from collections.abc import Sequence

from . import __version__
from .messages import Feedback, Goal, LogEntry, Result
from .names import action_name
from .vocab import EventType, Status, Tier

__all__ = ["main"]


def _demo(_: argparse.Namespace) -> int:
    print(f"action: {action_name('tinyRobot', 'tinyRobot1')}")
    goal = Goal(
        dynamic_event_seq=1, event_type=EventType.NEXT, category="go_to_place", description='"pantry"', id=1
    )
    print(f"goal:     {goal.to_json()}")
    feedback = Feedback(
        status=Status.UNDERWAY,
        id=1,
        logs=(LogEntry(seq=0, tier=Tier.INFO, unix_millis_time=0, text="moving"),),
    )
    print(f"feedback: {feedback.to_json()}")
    print(f"result:   {Result(status=Status.COMPLETED, id=1).to_json()}")
    return 0


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``dynevent`` command; return its exit code."""
    parser = argparse.ArgumentParser(prog="dynevent", description=__doc__)
    parser.add_argument("--version", action="version", version=f"dynevent {__version__}")
    commands = parser.add_subparsers(dest="command")
    demo = commands.add_parser("demo", help="show a short scripted exchange")
    demo.set_defaults(run=_demo)
    args = parser.parse_args(argv)
    if args.command is None:
        args = parser.parse_args(["demo"])
    result: int = args.run(args)
    return result
