"""The ``dynevent`` command line."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

from . import __version__, check, demo, explain
from .diagram import FORMATS, render

__all__ = ["main"]

_EPILOG = (
    "Without a command, runs the demo.  Exit status: 0 ok, 1 findings or failures (check: violations; "
    "explain: the goal is refused; vectors: a vector fails), 2 usage or input errors.  See docs/cli.md."
)


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


def _diagram(args: argparse.Namespace) -> int:
    print(render(args.format), end="")
    return 0


def _add_diagram_command(commands: argparse._SubParsersAction[argparse.ArgumentParser]) -> None:
    parser = commands.add_parser(
        "diagram",
        help="print the server's phase diagram",
        description="Print the server machine's phase diagram, drawn from dynevent.machine.TRANSITIONS "
        "(the Mermaid form is the one docs/spec.md embeds).  Exit status: 0.",
    )
    parser.add_argument(
        "--format", choices=FORMATS, default="mermaid", help="mermaid (the default) or dot (Graphviz)"
    )
    parser.set_defaults(run=_diagram)


def main(argv: Sequence[str] | None = None) -> int:
    """Run the ``dynevent`` command; return its exit code."""
    parser = argparse.ArgumentParser(prog="dynevent", description=__doc__, epilog=_EPILOG)
    parser.add_argument("--version", action="version", version=f"dynevent {__version__}")
    commands = parser.add_subparsers(dest="command")
    demo.add_command(commands)
    check.add_command(commands)
    explain.add_command(commands)
    _add_diagram_command(commands)
    _add_vectors_command(commands)
    args = parser.parse_args(argv)
    if args.command is None:
        args = parser.parse_args(["demo"])
    result: int = args.run(args)
    return result
