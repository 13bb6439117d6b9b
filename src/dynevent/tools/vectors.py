"""``dynevent vectors``: run the conformance vectors against dynevent or a driver, and print the outcomes.

The vectors, their runner and their reports are :mod:`dynevent.conformance.vectors`; this module reads
the files named, shows progress on a terminal, prints each outcome (text, or JSON lines as they end),
and writes ``--junit`` (:mod:`dynevent.files`).
"""

from __future__ import annotations

import argparse
import sys
import time

from dynevent import files
from dynevent.conformance import vectors
from dynevent.errors import FileError
from dynevent.interrupts import interruptible
from dynevent.tools._progress import Progress
from dynevent.wire import _json

__all__ = ["run"]


def run(args: argparse.Namespace) -> int:
    """``dynevent vectors``: run the conformance vectors; 0 all pass, 1 any fails, 2 bad input."""
    if args.files and not vectors.schema_validation_available():
        print(
            "dynevent vectors: note: jsonschema is not installed, so the files are checked by dynevent's "
            "own reader only; pip install 'dynevent[vectors]' to validate them against the schema",
            file=sys.stderr,
        )
    try:
        loaded = vectors.load_vectors(args.files)
    except vectors.InvalidVector as exc:
        print(f"dynevent vectors: invalid vector file: {exc}", file=sys.stderr)
        return 2
    if not loaded:
        print(f"dynevent vectors: no vector in {', '.join(args.files)}", file=sys.stderr)
        return 2
    chosen = vectors.select_vectors(loaded, args.filter)
    if not chosen:
        print(f"dynevent vectors: no vector matches {' or '.join(args.filter)}", file=sys.stderr)
        return 2
    implementation: vectors.InProcessImplementation | vectors.ExternalImplementation
    try:
        files.check_writable(args.junit, "--junit")
        if args.impl is None:
            implementation = vectors.InProcessImplementation()
        else:
            implementation = vectors.ExternalImplementation(args.impl, timeout=args.timeout)
    except (vectors.ImplementationError, FileError) as exc:
        print(f"dynevent vectors: {exc}", file=sys.stderr)
        return 2
    outcomes, took = _outcomes(args, chosen, implementation)
    if args.junit is not None:
        try:
            files.write_text(args.junit, vectors.junit_xml(outcomes, implementation.name), "--junit")
        except FileError as exc:
            print(f"dynevent vectors: {exc}", file=sys.stderr)
            return 2
    if args.json:
        print(_json.dumps(vectors.summary_record(outcomes, implementation.name, seconds=took)))
    else:
        print(vectors.format_report(outcomes, implementation.name))
        print(vectors.took_line(took))
    return 0 if all(outcome.passed for outcome in outcomes) else 1


def _outcomes(
    args: argparse.Namespace,
    chosen: list[vectors.Vector],
    implementation: vectors.InProcessImplementation | vectors.ExternalImplementation,
) -> tuple[list[vectors.Outcome], float]:
    """The vectors run, each outcome printed as it ends with ``--json``, with a progress line on a
    terminal; the outcomes and the seconds the run took.  The implementation is closed at the end."""
    progress = Progress("dynevent vectors", len(chosen))
    outcomes: list[vectors.Outcome] = []
    began = time.monotonic()
    try:
        with interruptible():  # Ctrl-C or SIGTERM, however inherited: the driver is ended as it stops
            for outcome in vectors.run_vectors(chosen, implementation, max_failures=args.max_failures):
                outcomes.append(outcome)
                if args.json:  # as it is known: a run cut short keeps a line for each vector it ran
                    progress.close()
                    print(_json.dumps(vectors.outcome_record(outcome)), flush=True)
                progress.update(len(outcomes), f"({len(outcomes)} of {len(chosen)}: {outcome.vector.name})")
    finally:
        progress.close()
        implementation.close()
    return outcomes, time.monotonic() - began
