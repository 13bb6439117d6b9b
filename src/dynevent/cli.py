"""The ``dynevent`` command line."""

from __future__ import annotations

import argparse
import sys
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


def _vectors(args: argparse.Namespace) -> int:
    """``dynevent vectors``: run the conformance vectors; 0 all pass, 1 any fails, 2 bad input."""
    from . import _json, vectors

    try:
        loaded = vectors.load_vectors(args.files)
    except vectors.InvalidVector as exc:
        print(f"dynevent vectors: invalid vector file: {exc}", file=sys.stderr)
        return 2
    chosen = vectors.select_vectors(loaded, args.filter)
    if not chosen:
        print(f"dynevent vectors: no vector matches {args.filter}", file=sys.stderr)
        return 2
    implementation: vectors.InProcessImplementation | vectors.ExternalImplementation
    try:
        if args.impl is None:
            implementation = vectors.InProcessImplementation()
        else:
            implementation = vectors.ExternalImplementation(args.impl, timeout=args.timeout)
    except vectors.ImplementationError as exc:
        print(f"dynevent vectors: {exc}", file=sys.stderr)
        return 2
    try:
        outcomes = list(vectors.run_vectors(chosen, implementation))
    finally:
        implementation.close()
    if args.json:
        for outcome in outcomes:
            print(_json.dumps(vectors.outcome_record(outcome)))
        print(_json.dumps(vectors.summary_record(outcomes, implementation.name)))
    else:
        print(vectors.format_report(outcomes, implementation.name))
    return 0 if all(outcome.passed for outcome in outcomes) else 1


def _add_vectors_command(commands: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    parser = commands.add_parser(
        "vectors",
        help="run the conformance vectors against an implementation",
        description="Run conformance vectors (the shipped ones, or FILEs) against dynevent in process "
        "or against COMMAND, a program speaking the driver protocol of docs/conformance.md.  Exit status: "
        "0 when every vector passes, 1 when one fails, 2 on a usage or vector-file error.",
    )
    parser.add_argument(
        "files", nargs="*", metavar="FILE", help="vector files (default: the shipped vectors)"
    )
    parser.add_argument("--impl", metavar="COMMAND", help="run COMMAND as the implementation under test")
    parser.add_argument(
        "--filter",
        metavar="NAME",
        action="append",
        help="only vectors whose name contains NAME, matches it as a glob, or cite it as a rule (R9.3); "
        "repeatable",
    )
    parser.add_argument(
        "--json", action="store_true", help="one JSON object per vector, then a summary object"
    )
    parser.add_argument(
        "--timeout", type=float, default=10.0, metavar="SECONDS", help="longest wait for one answer (10)"
    )
    parser.set_defaults(run=_vectors)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``dynevent`` command; return its exit code."""
    parser = argparse.ArgumentParser(prog="dynevent", description=__doc__)
    parser.add_argument("--version", action="version", version=f"dynevent {__version__}")
    commands = parser.add_subparsers(dest="command")
    demo = commands.add_parser("demo", help="show a short scripted exchange")
    demo.set_defaults(run=_demo)
    _add_vectors_command(commands)
    args = parser.parse_args(argv)
    if args.command is None:
        args = parser.parse_args(["demo"])
    result: int = args.run(args)
    return result
